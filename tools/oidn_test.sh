#!/usr/bin/env bash
# Builds luster with `--features oidn` against the Open Image Denoise 2.x
# shared libraries of the PyPI wheel `pyoidn` and runs the denoising tests.
#
# The wheel (pinned by version and SHA-256) is fetched once into
# target/oidn/ with `pip download`, and only what a CPU denoiser loads is
# unpacked: libOpenImageDenoise (the API), its core and CPU device modules,
# and oneTBB. The wheel carries no C headers; the `oidn` crate needs none.
# OIDN_DIR points the `oidn` crate's build script at target/oidn/<ver>, and
# luster's build script records OIDN_DIR/lib as the binaries' run path, so
# the tests' `luster` runs without LD_LIBRARY_PATH.
#
# Needs python3 with pip (installed with apt-get when absent and running as
# root) and network access to PyPI and crates.io. Exit code 0 when every
# test passed. Environment:
#   OIDN_DIR  use this OIDN 2.x installation (with lib/) instead of the wheel
set -euo pipefail
cd "$(dirname "$0")/.."
say() { echo "oidn_test: $*"; }
fail() {
    echo "oidn_test: FAIL: $*" >&2
    exit 1
}

version=2.5.1.0
wheel=pyoidn-$version-py3-none-manylinux2014_x86_64.whl
sha256=32ad13368f8de1ef63001942ad05b02a00cd732d1206d97f352d3a3f606d823e

if [ -z "${OIDN_DIR:-}" ]; then
    [ "$(uname -s)-$(uname -m)" = Linux-x86_64 ] ||
        fail "the pyoidn wheel is for Linux x86-64; on this machine set OIDN_DIR to an OIDN 2.x installation"
    cache=$PWD/target/oidn
    mkdir -p "$cache"
    if [ ! -f "$cache/$wheel" ]; then
        if ! python3 -m pip --version >/dev/null 2>&1; then
            [ "$(id -u)" = 0 ] || fail "python3 has no pip; install it (Debian: apt-get install python3-pip)"
            say "installing python3-pip"
            apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-pip >/dev/null
        fi
        say "downloading $wheel"
        python3 -m pip download --quiet --no-deps --only-binary=:all: -d "$cache/dl" "pyoidn==$version"
        mv "$cache/dl/$wheel" "$cache/$wheel"
    fi
    echo "$sha256  $cache/$wheel" | sha256sum --check --quiet - ||
        fail "$cache/$wheel does not have the expected SHA-256 (delete it to download it again)"
    OIDN_DIR=$cache/$version
    if [ ! -f "$OIDN_DIR/lib/libOpenImageDenoise.so" ]; then
        say "unpacking the CPU libraries into $OIDN_DIR"
        rm -rf "$OIDN_DIR.tmp"
        # A wheel is a zip; python3's zipfile needs no unzip on the machine.
        python3 - "$cache/$wheel" "$OIDN_DIR.tmp/lib" <<'EOF'
import os, re, sys, zipfile
wheel, dest = sys.argv[1], sys.argv[2]
os.makedirs(dest)
keep = re.compile(r"pyoidn/oidn/lib/(libOpenImageDenoise(_core|_device_cpu)?\.so[.0-9]*|libtbb\.so\.12[.0-9]*)$")
with zipfile.ZipFile(wheel) as z:
    for name in z.namelist():
        if keep.match(name):
            with z.open(name) as src, open(os.path.join(dest, os.path.basename(name)), "wb") as out:
                out.write(src.read())
EOF
        mv "$OIDN_DIR.tmp" "$OIDN_DIR"
    fi
fi
export OIDN_DIR
[ -e "$OIDN_DIR/lib/libOpenImageDenoise.so" ] || fail "$OIDN_DIR/lib/libOpenImageDenoise.so is missing"

say "OIDN_DIR=$OIDN_DIR"
cargo clippy --release -p luster --features oidn --all-targets --quiet -- -D warnings
cargo test --release -p luster --features oidn --lib --quiet -- denoise
cargo test --release -p luster --features oidn --test it --quiet -- denoise
say "passed"
