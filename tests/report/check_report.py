"""Open a gallery's index.html in headless Chromium and check that every image decodes.

    python3 check_report.py CHROMIUM PAGE.html SCREENSHOT.png

Drives the browser over the DevTools protocol on --remote-debugging-pipe (standard library
only): loads the page from file://, waits for the load event, then for every <img> awaits
img.decode() and reads naturalWidth (a missing image shows in the network log, a corrupt one
only here), checks that every relative link points at a file beside the page, and takes a
full-page screenshot. Prints a JSON summary; exit status 0 when every image decoded and no
link is dead, 1 otherwise (or when the browser fails).
"""

import base64
import json
import os
import subprocess
import sys
import tempfile
import time

TIMEOUT_S = 60


class Browser:
    def __init__(self, chromium):
        self.profile = tempfile.mkdtemp(prefix="wearcoef-chromium-")
        # The browser reads commands on fd 3 and writes replies on fd 4.
        to_browser_r, self.to_browser = os.pipe()
        self.from_browser, from_browser_w = os.pipe()

        def fds():
            os.dup2(to_browser_r, 3)
            os.dup2(from_browser_w, 4)

        self.proc = subprocess.Popen(
            [chromium, "--headless=new", "--no-sandbox", "--disable-gpu",
             "--remote-debugging-pipe", "--no-first-run", "--no-default-browser-check",
             f"--user-data-dir={self.profile}", "--window-size=1100,900", "about:blank"],
            # close_fds runs after preexec_fn: keep 3 and 4 open through it.
            pass_fds=(to_browser_r, from_browser_w, 3, 4), preexec_fn=fds,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_browser_r)
        os.close(from_browser_w)
        self.buffer = b""
        self.next_id = 0
        self.events = []

    def _read_message(self, deadline):
        while b"\0" not in self.buffer:
            if time.time() > deadline:
                raise TimeoutError("no reply from the browser")
            chunk = os.read(self.from_browser, 1 << 16)
            if not chunk:
                raise RuntimeError("the browser closed the pipe")
            self.buffer += chunk
        message, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(message)

    def send(self, method, params=None, session=None):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self.to_browser, json.dumps(msg).encode() + b"\0")
        deadline = time.time() + TIMEOUT_S
        while True:
            reply = self._read_message(deadline)
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            self.events.append(reply)

    def wait_event(self, method):
        deadline = time.time() + TIMEOUT_S
        while True:
            for i, e in enumerate(self.events):
                if e.get("method") == method:
                    return self.events.pop(i)
            self.events.append(self._read_message(deadline))

    def close(self):
        try:
            self.send("Browser.close")
        except Exception:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        subprocess.run(["rm", "-rf", self.profile], check=False)


CHECK_IMAGES = """
Promise.all([...document.images].map(img =>
    img.decode().then(() => img.naturalWidth > 0, () => false)
        .then(ok => ({src: img.getAttribute('src'), ok, width: img.naturalWidth}))))
    .then(r => JSON.stringify(r))
"""


def main(chromium, page, screenshot):
    browser = Browser(chromium)
    try:
        targets = browser.send("Target.getTargets")["targetInfos"]
        target = next(t["targetId"] for t in targets if t["type"] == "page")
        session = browser.send("Target.attachToTarget",
                               {"targetId": target, "flatten": True})["sessionId"]
        browser.send("Page.enable", session=session)
        browser.send("Page.navigate", {"url": "file://" + os.path.abspath(page)}, session)
        browser.wait_event("Page.loadEventFired")
        result = browser.send("Runtime.evaluate", {"expression": CHECK_IMAGES,
                              "awaitPromise": True, "returnByValue": True}, session)
        images = json.loads(result["result"]["value"])
        links = browser.send("Runtime.evaluate", {
            "expression": "JSON.stringify([...document.links].map(a => a.getAttribute('href')))",
            "returnByValue": True}, session)
        hrefs = json.loads(links["result"]["value"])
        shot = browser.send("Page.captureScreenshot",
                            {"format": "png", "captureBeyondViewport": True}, session)
        data = base64.b64decode(shot["data"])
        with open(screenshot, "wb") as f:
            f.write(data)
    finally:
        browser.close()
    bad = [i["src"] for i in images if not i["ok"]]
    # Links to files beside the page (data, vector images) must point at files that exist.
    here = os.path.dirname(os.path.abspath(page))
    dead = [h for h in hrefs if "://" not in h and not h.startswith("#")
            and not os.path.isfile(os.path.join(here, h))]
    print(json.dumps({"page": page, "images": len(images), "failed": bad, "links": len(hrefs),
                      "dead_links": dead, "screenshot_bytes": len(data)}))
    ok = images and not bad and not dead and data[:8] == b"\x89PNG\r\n\x1a\n"
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
