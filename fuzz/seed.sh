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
mkdir -p corpus/watch_request
seed() { printf '%b' "$2" > "corpus/watch_request/$1"; }
seed get 'GET /state HTTP/1.1\r\nHost: 127.0.0.1:8795\r\n\r\n'
seed browser 'GET /frame.png?n=12 HTTP/1.1\r\nHost: localhost:8795\r\nConnection: keep-alive\r\nUser-Agent: Mozilla/5.0\r\nAccept: */*\r\nSec-Fetch-Site: same-origin\r\nReferer: http://localhost:8795/\r\nAccept-Encoding: gzip, deflate\r\nCookie: a=1; b=2\r\n\r\n'
seed events 'GET /events HTTP/1.1\r\nHost: [::1]:8795\r\nAccept: text/event-stream\r\nCache-Control: no-cache\r\n\r\n'
seed pipelined 'POST /shader HTTP/1.1\r\nHost: 127.0.0.1:8795\r\nOrigin: http://127.0.0.1:8795\r\nContent-Length: 5\r\nExpect: 100-continue\r\n\r\nhelloHEAD / HTTP/1.0\r\nHost: localhost\r\nConnection: close\r\n\r\n'
seed refused 'POST / HTTP/1.1\r\nHost: evil.example\r\nTransfer-Encoding: chunked\r\nContent-Length: 99999999999\r\n\r\n0\r\n\r\n'
for t in corpus/*; do echo "$(ls "$t" | wc -l) seeds in $t"; done
