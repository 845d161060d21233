#!/usr/bin/env python3
"""viewer_screenshot.py URL OUT.png [WIDTH HEIGHT]

A screenshot of the 3-D viewer page at URL (served by `pointbake serve`)
once every model is loaded and drawn (window.pbViewer.ready), in headless
Chromium with WebGL on SwiftShader, as tools/check_viewer.py drives it. For
pictures in the docs (docs/viewer.md, README). Exit 1 when the page reports
an error or is not ready within two minutes.
"""
import base64, json, os, sys, tempfile, time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_viewer import Browser, TIMEOUT_S  # noqa: E402


def main():
    if len(sys.argv) not in (3, 5):
        sys.stderr.write(__doc__.split("\n\n")[0] + "\n")
        return 2
    url, out = sys.argv[1], sys.argv[2]
    width, height = (int(sys.argv[3]), int(sys.argv[4])) if len(sys.argv) == 5 else (1600, 900)
    base = url.split("/report/")[0] + "/"
    profile = tempfile.mkdtemp()
    browser = Browser(os.environ.get("CHROMIUM", "chromium"), profile, open(os.devnull, "wb"))
    try:
        target = browser.call("Target.createTarget", {"url": "about:blank"}, session=False)["targetId"]
        browser.session = browser.call("Target.attachToTarget", {"targetId": target, "flatten": True}, session=False)["sessionId"]
        for domain in ("Page", "Runtime", "Network"):
            browser.call(domain + ".enable", base=base)
        browser.call("Emulation.setDeviceMetricsOverride", {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}, base=base)
        browser.call("Page.navigate", {"url": url}, base=base)
        started, state = time.monotonic(), None
        while time.monotonic() - started < TIMEOUT_S:
            r = browser.call("Runtime.evaluate", {"expression": "JSON.stringify(window.pbViewer || null)", "returnByValue": True}, base=base)
            state = json.loads(r.get("result", {}).get("value") or "null")
            if state and (state.get("ready") or state.get("error")):
                break
            time.sleep(0.5)
        if not state or not state.get("ready") or browser.errors:
            sys.stderr.write("viewer_screenshot: %s %s\n" % ((state or {}).get("error"), "; ".join(browser.errors)))
            return 1
        time.sleep(1.5)  # the browser FPS figure
        png = base64.b64decode(browser.call("Page.captureScreenshot", {"format": "png"}, base=base)["data"])
        with open(out, "wb") as f:
            f.write(png)
        return 0
    finally:
        browser.close()
        os.system("rm -rf '%s'" % profile)


if __name__ == "__main__":
    sys.exit(main())
