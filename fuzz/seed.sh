#!/bin/sh
# Fills corpus/<target>/ with seeds: the course scenes (SHARED, default
# ../../shared/scenes/ceng795 from the repository root), the test fixtures and
# the example shaders, each at most 64 KiB so executions stay fast.
set -eu
cd "$(dirname "$0")"
root=..
shared=${SHARED:-$root/../shared/scenes/ceng795}
name() { echo "$1" | sed "s|^\(\.\./\)*||; s|/|_|g"; }
small() { find "$@" -type f -size -65k 2>/dev/null || true; }
add() { # target, files...
    t=$1; shift
    mkdir -p corpus/$t
    for f in "$@"; do cp "$f" "corpus/$t/$(name "$f")"; done
}
add scene_xml $(small "$shared" "$root/crates/luster/tests" -name '*.xml')
add scene_json $(small "$shared" "$root/crates/luster/tests" -name '*.json')
add ply $(small "$shared" "$root/crates/luster/tests" -name '*.ply')
add image $(small "$shared" "$root/crates/luster/tests" \( -name '*.png' -o -name '*.jpg' -o -name '*.exr' -o -name '*.hdr' \))
add shader $(small "$root/crates/luster/tests" "$root/examples" "$root/docs" -name '*.lua')
add partfile $(small seeds/partfile)
mkdir -p corpus/obj
for o in $(small "$root/crates/luster/tests" -name '*.obj'); do
    out="corpus/obj/$(name "$o")"
    cp "$o" "$out"
    for m in $(sed -n 's/^mtllib[[:space:]]*//p' "$o"); do
        [ -f "$(dirname "$o")/$m" ] && { printf '\n#-mtl-\n'; cat "$(dirname "$o")/$m"; } >> "$out"
    done
done
for t in corpus/*; do echo "$(ls "$t" | wc -l) seeds in $t"; done
