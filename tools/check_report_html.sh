#!/bin/sh
# check_report_html.sh REPORT_HTML SCREENSHOT_PNG
#
# Loads a report.html in headless Chromium (Debian `chromium`) with no
# network, fails if the page reports any error, and writes a screenshot of a
# fixed 1280x2000 window to SCREENSHOT_PNG that must not be blank.
#
# How: python3 (standard library only) drives one Chromium process over the
# DevTools protocol on a pipe (--remote-debugging-pipe, fds 3/4). The
# --screenshot flag alone reports no errors, and --enable-logging misses
# failed image loads, so the script listens to the page instead and fails on:
#   - Runtime.exceptionThrown          (script errors)
#   - Runtime.consoleAPICalled error   (console.error / console.assert)
#   - Log.entryAdded level "error"     (e.g. "Failed to load resource")
#   - Network.loadingFailed            (any resource that did not load)
#   - Network.requestWillBeSent to anything but file: or data: URLs
#     (the report must be self-contained: no network)
#   - a navigation error, or no load event within 60 s
# Blank check: the screenshot must be a PNG of exactly 1280x2000, and a
# quarter-scale capture of the same view must hold >= 32 distinct colors.
#
# Exit status: 0 pass, 1 fail, 2 usage, 77 Chromium missing and CI unset
# (ctest's SKIP_RETURN_CODE); with CI=true a missing Chromium fails.
# CHROMIUM=/path/to/chromium overrides the browser.
set -eu

if [ $# -ne 2 ]; then
  echo "usage: $0 REPORT_HTML SCREENSHOT_PNG" >&2
  exit 2
fi
html=$1
shot=$2

chromium=${CHROMIUM:-}
if [ -z "$chromium" ]; then
  chromium=$(command -v chromium 2>/dev/null || true)
fi
if [ -z "$chromium" ] || [ ! -x "$chromium" ]; then
  if [ "${CI:-}" = "true" ]; then
    echo "check_report_html: chromium not found (CI=true: failing; apt-get install chromium)" >&2
    exit 1
  fi
  echo "check_report_html: chromium not found; skipped (apt-get install chromium)" >&2
  exit 77
fi
if [ ! -f "$html" ]; then
  echo "check_report_html: $html: no such file" >&2
  exit 1
fi
if ! command -v python3 >/dev/null 2>&1; then
  echo "check_report_html: python3 not found" >&2
  exit 1
fi

profile=$(mktemp -d)
log=$(mktemp)
trap 'rm -rf "$profile" "$log"' EXIT

status=0
python3 - "$chromium" "$html" "$shot" "$profile" "$log" <<'PYTHON' || status=$?
import base64, json, os, select, subprocess, sys, time, zlib

chromium, html, shot, profile, log_path = sys.argv[1:6]
WIDTH, HEIGHT, MIN_COLORS, TIMEOUT_S = 1280, 2000, 32, 60.0
url = "file://" + os.path.abspath(html)

cmd_r, cmd_w = os.pipe()    # we write commands, Chromium reads fd 3
resp_r, resp_w = os.pipe()  # Chromium writes fd 4, we read


def child_fds():
    a, b = os.dup(cmd_r), os.dup(resp_w)  # out of the way of 3 and 4
    os.dup2(a, 3)
    os.dup2(b, 4)


log = open(log_path, "wb")
proc = subprocess.Popen(
    [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
     "--disable-background-networking", "--disable-component-update", "--disable-sync",
     "--user-data-dir=" + profile, "--remote-debugging-pipe", "--hide-scrollbars",
     "--window-size=%d,%d" % (WIDTH, HEIGHT), "about:blank"],
    stdin=subprocess.DEVNULL, stdout=log, stderr=log, preexec_fn=child_fds, close_fds=False)
os.close(cmd_r)
os.close(resp_w)

errors, events, pending = [], [], b""
next_id = [0]
deadline = time.monotonic() + TIMEOUT_S


def fail(message):
    sys.stderr.write("check_report_html: %s: %s\n" % (html, message))
    try:
        proc.kill()
    except Exception:
        pass
    sys.exit(1)


def read_messages(timeout):
    global pending
    ready, _, _ = select.select([resp_r], [], [], max(0.0, timeout))
    if not ready:
        return []
    chunk = os.read(resp_r, 1 << 20)
    if not chunk:
        fail("chromium closed the DevTools pipe (log: %s)" % open(log_path, "rb").read()[-2000:].decode("utf-8", "replace"))
    pending += chunk
    *messages, pending = pending.split(b"\0")
    return [json.loads(m) for m in messages if m]


def note(message):
    method, p = message.get("method"), message.get("params", {})
    if method == "Runtime.exceptionThrown":
        d = p.get("exceptionDetails", {})
        errors.append("script error: %s %s" % (d.get("text", ""), d.get("exception", {}).get("description", "")))
    elif method == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
        errors.append("console.%s: %s" % (p["type"], " ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", []))))
    elif method == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
        e = p["entry"]
        errors.append("%s error: %s %s" % (e.get("source", ""), e.get("text", ""), e.get("url", "")))
    elif method == "Network.loadingFailed":
        errors.append("failed to load a resource: %s (%s)" % (p.get("errorText", ""), p.get("requestId", "")))
    elif method == "Network.requestWillBeSent":
        u = p.get("request", {}).get("url", "")
        if not (u.startswith("file:") or u.startswith("data:") or u == "about:blank"):
            errors.append("network request (the report must be self-contained): " + u[:200])
    events.append(message)


def call(method, params=None, session=None):
    next_id[0] += 1
    message = {"id": next_id[0], "method": method, "params": params or {}}
    if session:
        message["sessionId"] = session
    os.write(cmd_w, json.dumps(message).encode() + b"\0")
    while True:
        if time.monotonic() > deadline:
            fail("timed out waiting for " + method)
        for m in read_messages(deadline - time.monotonic()):
            if m.get("id") == next_id[0]:
                if "error" in m:
                    fail("%s: %s" % (method, m["error"].get("message")))
                return m.get("result", {})
            note(m)


target = call("Target.createTarget", {"url": "about:blank"})["targetId"]
session = call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
for domain in ("Page", "Runtime", "Log", "Network"):
    call(domain + ".enable", session=session)
call("Emulation.setDeviceMetricsOverride",
     {"width": WIDTH, "height": HEIGHT, "deviceScaleFactor": 1, "mobile": False}, session=session)
nav = call("Page.navigate", {"url": url}, session=session)
if nav.get("errorText"):
    fail("navigation failed: " + nav["errorText"])
loaded = any(e.get("method") == "Page.loadEventFired" for e in events)
while not loaded:
    if time.monotonic() > deadline:
        fail("no load event within %.0f s" % TIMEOUT_S)
    for m in read_messages(deadline - time.monotonic()):
        note(m)
        loaded = loaded or m.get("method") == "Page.loadEventFired"
settle = time.monotonic() + 0.5  # late console messages / failed loads
while time.monotonic() < settle:
    for m in read_messages(settle - time.monotonic()):
        note(m)

png = base64.b64decode(call("Page.captureScreenshot", {"format": "png"}, session=session)["data"])
small = base64.b64decode(call("Page.captureScreenshot", {"format": "png", "clip": {
    "x": 0, "y": 0, "width": WIDTH, "height": HEIGHT, "scale": 0.25}}, session=session)["data"])
try:
    call("Browser.close")
except SystemExit:
    pass
try:
    proc.wait(timeout=10)
except subprocess.TimeoutExpired:
    proc.kill()

tmp = shot + ".tmp"
with open(tmp, "wb") as f:
    f.write(png)
os.replace(tmp, shot)


def png_pixels(data):
    """(width, height, set of RGB(A) tuples) of an 8-bit RGB/RGBA PNG."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length = int.from_bytes(data[pos:pos + 4], "big")
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height = int.from_bytes(body[0:4], "big"), int.from_bytes(body[4:8], "big")
            depth, color = body[8], body[9]
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    if depth != 8 or color not in (2, 6):
        raise ValueError("unexpected PNG depth %d / color type %d" % (depth, color))
    bpp = 3 if color == 2 else 4
    raw, stride = zlib.decompress(idat), width * bpp
    prev, colors, off = bytearray(stride), set(), 0
    for _ in range(height):
        ftype, line = raw[off], bytearray(raw[off + 1:off + 1 + stride])
        off += 1 + stride
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if ftype == 1:
                line[i] = (line[i] + a) & 255
            elif ftype == 2:
                line[i] = (line[i] + b) & 255
            elif ftype == 3:
                line[i] = (line[i] + ((a + b) >> 1)) & 255
            elif ftype == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        colors.update(bytes(line[i:i + 3]) for i in range(0, stride, bpp))
        prev = line
    return width, height, colors


def png_size(data):
    if data[:8] != b"\x89PNG\r\n\x1a\n" or data[12:16] != b"IHDR":
        raise ValueError("not a PNG")
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


try:
    size = png_size(png)
    _, _, colors = png_pixels(small)
except (ValueError, zlib.error, IndexError) as e:
    fail("screenshot is not a readable PNG: %s" % e)
if size != (WIDTH, HEIGHT):
    errors.append("screenshot is %dx%d, expected %dx%d" % (size + (WIDTH, HEIGHT)))
if len(colors) < MIN_COLORS:
    errors.append("screenshot looks blank: %d distinct colors (< %d)" % (len(colors), MIN_COLORS))
if errors:
    for e in errors:
        sys.stderr.write("check_report_html: %s: %s\n" % (html, e))
    sys.exit(1)
print("check_report_html: %s: loaded without errors; screenshot %s (%dx%d, %d colors at 1/4 scale)"
      % (html, shot, WIDTH, HEIGHT, len(colors)))
PYTHON
exit $status
