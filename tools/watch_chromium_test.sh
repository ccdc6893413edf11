#!/usr/bin/env bash
# End-to-end test of `luster watch` in a real browser: Debian's headless
# Chromium, driven over the DevTools protocol by the Python script below
# (standard library only).
#
# Starts `luster watch` on a small scene with a shader, opens its page, and
# waits until the page shows the first frame (the page exposes the frame
# number and the colour of the image's centre pixel, as the browser decoded
# it, on <body>); then saves the shader with another colour and checks the
# page's image changed at the object; then saves a syntax error and checks
# the page shows it (with the script's file:line) over the kept image.
# Then the shader editor: the page has opened look.lua in CodeMirror with the
# error marked at its line; the test replaces the text through the editor
# (the view's dispatch), clicks Save and sees the file written and new
# pixels; saves a syntax error from the editor and sees CodeMirror's lint
# mark on the line Lua names; fixes it, and moves the params{} slider and
# sees the image darken.
# Installs Debian's chromium when absent (needs root then). Exit code 0 only
# when everything was seen; never skips. Environment:
#   LUSTER  the binary (default target/release/luster, built if missing)
#   SHOT    also save the page's screenshot (with the error overlay) there
#   KEEP=1  keep the temporary folder
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$PWD
say() { echo "watch_chromium: $*"; }
fail() {
    echo "watch_chromium: FAIL: $*" >&2
    exit 1
}

browser=""
for b in chromium chromium-browser; do
    command -v "$b" >/dev/null && browser=$b && break
done
if [ -z "$browser" ]; then
    [ "$(id -u)" = 0 ] || fail "chromium is not installed, and installing it needs root"
    say "installing chromium"
    export DEBIAN_FRONTEND=noninteractive
    # A registry hiccup on a fresh CI machine should not fail the run: retry.
    for attempt in 1 2 3; do
        if apt-get update -qq >/dev/null \
            && apt-get install -y -qq --no-install-recommends chromium >/dev/null; then
            break
        fi
        [ "$attempt" = 3 ] && fail "could not install chromium"
        sleep 10
    done
    browser=chromium
fi
command -v python3 >/dev/null || fail "python3 is missing"

luster=${LUSTER:-$repo/target/release/luster}
if [ ! -x "$luster" ]; then
    say "building luster"
    cargo build --release --quiet
fi

tmp=$(mktemp -d)
pids=()
cleanup() {
    for p in "${pids[@]}"; do
        kill "$p" 2>/dev/null || true
    done
    wait 2>/dev/null || true
    # Chromium's helper processes can still be writing into the profile
    # when the browser is killed: retry, and never let cleanup decide the
    # test's exit status.
    if [ "${KEEP:-}" = 1 ]; then
        say "kept $tmp"
    else
        for _ in 1 2 3 4 5; do
            rm -rf "$tmp" 2>/dev/null && break
            sleep 1
        done
    fi
    return 0
}
trap cleanup EXIT

cat >"$tmp/scene.xml" <<'XML'
<Scene>
    <BackgroundColor>25 27 33</BackgroundColor>
    <Cameras>
        <Camera id="1" type="lookAt">
            <Position>0 1.2 4</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
            <FovY>40</FovY><NearDistance>1</NearDistance>
            <ImageResolution>480 320</ImageResolution><NumSamples>4</NumSamples>
            <ImageName>watch.png</ImageName>
        </Camera>
    </Cameras>
    <Lights>
        <AmbientLight>50 50 50</AmbientLight>
        <PointLight id="1"><Position>3 5 5</Position><Intensity>30000 30000 30000</Intensity></PointLight>
    </Lights>
    <Materials>
        <Material id="1">
            <AmbientReflectance>1 1 1</AmbientReflectance><DiffuseReflectance>1 1 1</DiffuseReflectance>
            <SpecularReflectance>0.3 0.3 0.3</SpecularReflectance><PhongExponent>40</PhongExponent>
        </Material>
    </Materials>
    <Textures>
        <TextureMap id="1" type="shader"><Shader>look.lua</Shader><DecalMode>replace_kd</DecalMode></TextureMap>
    </Textures>
    <VertexData>0 0 0</VertexData>
    <Objects>
        <Sphere id="1"><Material>1</Material><Textures>1</Textures><Center>1</Center><Radius>1</Radius></Sphere>
        <Plane id="2"><Material>1</Material><Point>1</Point><Normal>0 1 0</Normal></Plane>
    </Objects>
</Scene>
XML
stripes() { # r g b: stripes of that colour and white
    printf 'function color(s)\n  local t = math.floor(s.P.y * 8) %% 2\n  return t == 0 and vec3(%s, %s, %s) or vec3(0.9, 0.9, 0.9)\nend\n' "$1" "$2" "$3"
}
stripes 0.9 0.1 0.1 >"$tmp/look.lua"

(cd "$tmp" && exec "$luster" watch scene.xml --port 0 --threads 2 >watch.out 2>watch.err) &
pids+=($!)
for _ in $(seq 100); do
    grep -q 'http://' "$tmp/watch.out" 2>/dev/null && break
    sleep 0.1
done
url=$(grep -o 'http://[^ ]*' "$tmp/watch.out" || true)
[ -n "$url" ] || fail "luster watch printed no address: $(cat "$tmp/watch.err")"
say "luster watch serves $url"

"$browser" --headless --no-sandbox --disable-gpu --no-first-run --disable-extensions \
    --user-data-dir="$tmp/profile" --remote-debugging-port=0 --window-size=800,520 about:blank \
    >"$tmp/chromium.log" 2>&1 &
pids+=($!)

python3 - "$tmp" "$url" "${SHOT:-}" <<'PY' || fail "see above"
"""Drives the page over the DevTools protocol (a minimal WebSocket client)."""
import base64, functools, json, os, socket, struct, sys, time, urllib.parse, urllib.request

print = functools.partial(print, flush=True)

tmp, url, shot = sys.argv[1], sys.argv[2], sys.argv[3]
LIMIT = 30.0


def fail(msg):
    print(f"watch_chromium: FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


def devtools_port():
    end = time.time() + LIMIT
    path = os.path.join(tmp, "profile", "DevToolsActivePort")
    while time.time() < end:
        try:
            with open(path) as f:
                return int(f.readline())
        except (OSError, ValueError):
            time.sleep(0.1)
    fail("chromium did not open its DevTools port")


class Tab:
    def __init__(self, ws_url):
        u = urllib.parse.urlparse(ws_url)
        self.s = socket.create_connection((u.hostname, u.port), timeout=LIMIT)
        key = base64.b64encode(os.urandom(16)).decode()
        self.s.sendall((f"GET {u.path} HTTP/1.1\r\nHost: {u.hostname}:{u.port}\r\nUpgrade: websocket\r\n"
                        f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
        head = b""
        while b"\r\n\r\n" not in head:
            c = self.s.recv(1)
            if not c:
                fail("the DevTools socket closed during the handshake")
            head += c
        if b" 101 " not in head.split(b"\r\n")[0]:
            fail("the DevTools socket refused the WebSocket handshake")
        self.next_id = 0

    def _exact(self, n):
        b = b""
        while len(b) < n:
            c = self.s.recv(n - len(b))
            if not c:
                fail("the DevTools socket closed")
            b += c
        return b

    def _send(self, data):
        n = len(data)
        head = bytearray([0x81])
        if n < 126:
            head.append(0x80 | n)
        elif n < 65536:
            head += bytes([0x80 | 126]) + struct.pack(">H", n)
        else:
            head += bytes([0x80 | 127]) + struct.pack(">Q", n)
        mask = os.urandom(4)
        self.s.sendall(bytes(head) + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(data)))

    def _message(self):
        parts = []
        while True:
            b0, b1 = self._exact(2)
            n = b1 & 0x7F
            if n == 126:
                n = struct.unpack(">H", self._exact(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", self._exact(8))[0]
            payload = self._exact(n)
            if b0 & 0x0F in (0x9, 0xA):  # ping, pong
                continue
            parts.append(payload)
            if b0 & 0x80:
                return json.loads(b"".join(parts))

    def call(self, method, **params):
        self.next_id += 1
        self._send(json.dumps({"id": self.next_id, "method": method, "params": params}).encode())
        while True:
            m = self._message()
            if m.get("id") == self.next_id:
                if "error" in m:
                    fail(f"{method}: {m['error']}")
                return m["result"]


def state():
    with urllib.request.urlopen(url + "state", timeout=LIMIT) as r:
        return json.load(r)


def dataset(tab):
    r = tab.call("Runtime.evaluate", expression="JSON.stringify(document.body ? document.body.dataset : {})",
                 returnByValue=True)
    d = {"frame": "0", "center": "", "error": "", "spp": "0"}
    d.update(json.loads(r["result"].get("value", "{}")))  # nothing while the page loads
    return d


def settle(tab, what, ok):
    """The page's dataset once the render is done and `ok` holds."""
    end = time.time() + LIMIT
    while time.time() < end:
        s, d = state(), dataset(tab)
        if not s["busy"] and ok(s, d):
            return s, d
        time.sleep(0.1)
    fail(f"the page never showed {what}; last page state {d}, server state {s}")


def save(text):
    """Writes look.lua as editors do: a new file renamed over the old one."""
    path = os.path.join(tmp, "look.lua")
    with open(path + ".new", "w") as f:
        f.write(text)
    os.replace(path + ".new", path)


def rgb(d):
    return [int(v) for v in d["center"].split(",")]


port = devtools_port()
with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=LIMIT) as r:
    pages = [t for t in json.load(r) if t.get("type") == "page"]
if not pages:
    fail("chromium has no page to drive")
tab = Tab(pages[0]["webSocketDebuggerUrl"])
tab.call("Page.navigate", url=url)

s, d = settle(tab, "the first frame", lambda s, d: s["frame"] and d["frame"] == str(s["frame"]) and d["center"])
red = rgb(d)
print(f"watch_chromium: frame {d['frame']}, {s['spp']} spp, centre pixel {red}")
if not (red[0] > red[1] + 60 and red[0] > red[2] + 60):
    fail(f"the sphere's centre is not the red stripe: {red}")

save("function color(s)\n  local t = math.floor(s.P.y * 8) % 2\n"
     "  return t == 0 and vec3(0.1, 0.3, 0.9) or vec3(0.9, 0.9, 0.9)\nend\n")
first = int(d["frame"])
s, d = settle(tab, "a new frame after the save",
              lambda s, d: s["frame"] > first and d["frame"] == str(s["frame"]) and d["center"])
blue = rgb(d)
print(f"watch_chromium: after the save: frame {d['frame']}, {s['spp']} spp, centre pixel {blue}")
if not (blue[2] > blue[0] + 60 and blue[2] > blue[1] + 30):
    fail(f"the page's image did not change to the blue stripe: {blue}")

save("function color(s)\n  local t = math.floor(s.P.y * 8) % 2\n  return vec3(0.1, 0.3, 0.9\nend\n")
kept = d["frame"]
s, d = settle(tab, "the syntax error", lambda s, d: "look.lua:4" in d["error"])
print(f"watch_chromium: error shown: {d['error']}")
if d["frame"] != kept or rgb(d) != blue:
    fail("the last good image was not kept under the error")
shown = tab.call("Runtime.evaluate", expression="getComputedStyle(document.getElementById('error')).display",
                 returnByValue=True)["result"]["value"]
if shown != "block":
    fail("the error overlay is not visible")

# The shader editor.
def js(expr):
    r = tab.call("Runtime.evaluate", expression=expr, returnByValue=True)
    if "exceptionDetails" in r:
        fail(f"{expr}: {r['exceptionDetails']}")
    return r["result"].get("value")


def wait_page(what, expr):
    end = time.time() + LIMIT
    while time.time() < end:
        v = js(expr)
        if v:
            return v
        time.sleep(0.1)
    fail(f"the page never showed {what}; page state {dataset(tab)}")


LINT_LINE = """(() => {
  const r = document.querySelector('.cm-lintRange-error');
  if (!r) return 0;
  return [...document.querySelectorAll('.cm-content .cm-line')].indexOf(r.closest('.cm-line')) + 1;
})()"""


def edit_and_save(text):
    saves = int(js("document.body.dataset.saves"))
    js("lusterEditor.dispatch({changes: {from: 0, to: lusterEditor.state.doc.length, insert: %s}})"
       % json.dumps(text))
    js("document.getElementById('save').click()")
    wait_page("the save's answer", f"Number(document.body.dataset.saves) > {saves}")
    with open(os.path.join(tmp, "look.lua")) as f:
        if f.read() != text:
            fail("the editor's save did not write the text to look.lua")


wait_page("look.lua in the editor", "document.body.dataset.file === 'look.lua' && !!window.lusterEditor")
line = wait_page("the error marked in the editor", LINT_LINE)
if line != 4:
    fail(f"the editor marks line {line}, not the error's line 4")
print("watch_chromium: the editor marks look.lua line 4")

tinted = ("params{ tint = rgb(0.1, 0.8, 0.1), gain = range(1, 0, 1) }\n"
          "function color(s)\n  local t = math.floor(s.P.y * 8) % 2\n"
          "  return t == 0 and param.tint * param.gain or vec3(0.9, 0.9, 0.9)\nend\n")
edit_and_save(tinted)
kept = int(d["frame"])
s, d = settle(tab, "a new frame after the editor's save",
              lambda s, d: s["frame"] > kept and not s["error"] and d["frame"] == str(s["frame"]))
green = rgb(d)
print(f"watch_chromium: after the editor's save: frame {d['frame']}, centre pixel {green}")
if not (green[1] > green[0] + 60 and green[1] > green[2] + 60):
    fail(f"the page's image did not change to the green stripe: {green}")
if js(LINT_LINE) != 0:
    fail("the error mark stayed after a good render")

edit_and_save("params{ gain = range(1, 0, 1) }\nfunction color(s)\n  local x = = 1\nend\n")
s, d = settle(tab, "the editor's syntax error", lambda s, d: "look.lua:3" in d["error"])
line = wait_page("the syntax error marked in the editor", LINT_LINE)
if line != 3:
    fail(f"the editor marks line {line}, not the error's line 3")
print("watch_chromium: a syntax error saved from the editor is marked at line 3")

edit_and_save(tinted)
kept = int(d["frame"])
s, d = settle(tab, "the fixed render", lambda s, d: s["frame"] > kept and not s["error"]
              and d["frame"] == str(s["frame"]) and s["spp"] == s["target_spp"])
before = rgb(d)
wait_page("the gain slider", "!!document.querySelector('input[type=range][data-param=gain]')")
kept = int(d["frame"])
js("(() => { const i = document.querySelector('input[type=range][data-param=gain]');"
   " i.value = 0.25; i.dispatchEvent(new Event('input', {bubbles: true})); })()")
s, d = settle(tab, "a new frame after the slider moved",
              lambda s, d: s["frame"] > kept and d["frame"] == str(s["frame"]) and rgb(d)[1] < before[1] - 60)
print(f"watch_chromium: slider gain 1 -> 0.25: centre pixel {before} -> {rgb(d)}")
with open(os.path.join(tmp, "look.lua")) as f:
    if f.read() != tinted:
        fail("the slider wrote to the script")

if shot:
    png = base64.b64decode(tab.call("Page.captureScreenshot", format="png")["data"])
    with open(shot, "wb") as f:
        f.write(png)
    print(f"watch_chromium: screenshot saved to {shot}")
PY
say "PASS"
