#!/usr/bin/env python3
"""Mean LDR-FLIP of the image pairs in tests/fixtures/flip/, by NVIDIA's
reference implementation (the `flip-evaluator` package from PyPI), printed as
the table that tests/flip_reference.rs checks luster's LDR-FLIP against.

    python3 -m venv /tmp/flipenv && /tmp/flipenv/bin/pip install flip-evaluator==1.7
    /tmp/flipenv/bin/python tools/flip_reference.py

Defaults of both: LDR, sRGB inputs, 67 pixels per degree.
"""
import pathlib

import flip_evaluator as flip

FIXTURES = pathlib.Path(__file__).resolve().parent.parent / "tests" / "fixtures" / "flip"

for ref in sorted(FIXTURES.glob("*_ref.png")):
    name = ref.name[: -len("_ref.png")]
    test = ref.with_name(f"{name}_test.png")
    _, mean, _ = flip.evaluate(str(ref), str(test), "LDR", applyMagma=False)
    print(f'    ("{name}", {mean:.6f}),')
