#!/usr/bin/env python3
"""Mean FLIP of the image pairs in crates/luster/tests/fixtures/flip/, by NVIDIA's
reference implementation (the `flip-evaluator` package from PyPI), printed as
the two tables that crates/luster/tests/it/flip_reference.rs checks luster's FLIP against:
LDR-FLIP of the `*_ref.png` / `*_test.png` pairs, HDR-FLIP of the
`*_ref.exr` / `*_test.exr` pairs.

    python3 -m venv /tmp/flipenv && /tmp/flipenv/bin/pip install flip-evaluator==1.7
    /tmp/flipenv/bin/python tools/flip_reference.py

Defaults of both: 67 pixels per degree; LDR inputs sRGB-encoded; HDR inputs
linear, exposures and the ACES tone mapper chosen by FLIP.
"""
import pathlib

import flip_evaluator as flip

FIXTURES = pathlib.Path(__file__).resolve().parent.parent / "crates" / "luster" / "tests" / "fixtures" / "flip"

for ext, mode in (("png", "LDR"), ("exr", "HDR")):
    print(f"{mode}:")
    for ref in sorted(FIXTURES.glob(f"*_ref.{ext}")):
        name = ref.name[: -len(f"_ref.{ext}")]
        test = ref.with_name(f"{name}_test.{ext}")
        _, mean, _ = flip.evaluate(str(ref), str(test), mode, applyMagma=False)
        print(f'    ("{name}", {mean:.6f}),')
