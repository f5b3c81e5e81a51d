"""Headless Chromium driven over the DevTools protocol, to check and photograph reports.

:class:`Chromium` starts Debian's ``chromium`` headless with networking features off and a fresh
profile folder, opens one page and records what a check needs: console errors, uncaught
exceptions, log errors and every network request the page makes (``data:`` URIs and the page's
own ``file://`` URL excepted, since they fetch nothing). It evaluates JavaScript, moves and
clicks the mouse, and takes PNG screenshots. The protocol goes over a WebSocket
(``websocket-client``, a test dependency).

>>> with Chromium() as browser:                                   # doctest: +SKIP
...     browser.open("report.html")
...     browser.evaluate("document.querySelectorAll('#chart .pt').length")
1150
"""
from __future__ import annotations

import base64
import json
import os
import shutil
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path
from typing import Optional

from rrcache.errors import RRCacheError

#: flags that keep a headless Chromium from reaching the network by itself
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-component-update", "--disable-sync", "--disable-background-networking",
         "--disable-default-apps", "--disable-extensions", "--disable-breakpad", "--no-default-browser-check",
         "--hide-scrollbars", "--mute-audio", "--remote-allow-origins=*")
#: with ``webgl=True``: WebGL2 on the CPU (ANGLE over SwiftShader) in place of --disable-gpu, so a
#: page's WebGL2 renders the same on a machine without a GPU (newer Chromiums no longer fall back
#: to SwiftShader by themselves)
WEBGL_FLAGS = ("--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist")


def find_chromium() -> Optional[str]:
    """The Chromium executable (``$CHROMIUM``, then ``chromium``/``chromium-browser`` on PATH), or None."""
    for candidate in (os.environ.get("CHROMIUM"), "chromium", "chromium-browser"):
        if candidate and shutil.which(candidate):
            return shutil.which(candidate)
    return None


class Chromium:
    """One headless Chromium with one page (see the module docstring); use it in a ``with`` block."""

    def __init__(self, width: int = 1280, height: int = 900, executable: Optional[str] = None,
                 timeout: float = 30.0, webgl: bool = False):
        try:
            import websocket
        except ImportError:
            raise RRCacheError("the browser checks need the websocket-client package", "rrcache.report.browser",
                               hint="pip install -e '.[test]'") from None
        self.executable = executable or find_chromium()
        if self.executable is None:
            raise RRCacheError("no Chromium found", "PATH", hint="apt-get install -y chromium")
        self.timeout = timeout
        self.events: list[dict] = []
        self._id = 0
        self._dir = tempfile.mkdtemp(prefix="rrcache-chromium-")
        self._log = tempfile.TemporaryFile()  # Chromium's own messages (a pipe could fill and stall it)
        flags = tuple(f for f in FLAGS if f != "--disable-gpu") + WEBGL_FLAGS if webgl else FLAGS
        self._proc = subprocess.Popen(
            [self.executable, *flags, f"--user-data-dir={self._dir}", "--remote-debugging-port=0",
             f"--window-size={width},{height}", "about:blank"],
            stdout=subprocess.DEVNULL, stderr=self._log)
        try:
            port = self._port()
            page = self._page_target(port)
            self._ws = websocket.create_connection(page, timeout=timeout, suppress_origin=True)
            for domain in ("Page", "Runtime", "Log", "Network"):
                self.send(f"{domain}.enable")
            self.send("Emulation.setDeviceMetricsOverride", width=width, height=height, deviceScaleFactor=1,
                      mobile=False)
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------ start-up
    def _port(self) -> int:
        marker = Path(self._dir) / "DevToolsActivePort"
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            if self._proc.poll() is not None:
                self._log.seek(0)
                err = self._log.read().decode(errors="replace")[-800:]
                raise RRCacheError(f"Chromium exited at start ({self._proc.returncode}): {err.strip()}",
                                   self.executable, hint="run it by hand with --headless to see why")
            if marker.exists():
                text = marker.read_text().split()
                if text:
                    return int(text[0])
            time.sleep(0.05)
        raise RRCacheError("Chromium did not open its DevTools port", self.executable,
                           hint="a slow machine: give a longer timeout")

    def _page_target(self, port: int) -> str:
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=self.timeout) as reply:
                targets = json.loads(reply.read())
            pages = [t for t in targets if t.get("type") == "page"]
            if pages:
                return pages[0]["webSocketDebuggerUrl"]
            time.sleep(0.05)
        raise RRCacheError("Chromium opened no page", self.executable)

    # ------------------------------------------------------------------ protocol
    def send(self, method: str, **params) -> dict:
        """Call a DevTools method and return its result; events that arrive meanwhile are kept."""
        self._id += 1
        call = self._id
        self._ws.send(json.dumps({"id": call, "method": method, "params": params}))
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            message = json.loads(self._ws.recv())
            if message.get("id") == call:
                if "error" in message:
                    raise RRCacheError(f"DevTools {method}: {message['error'].get('message')}", "chromium")
                return message.get("result", {})
            if "method" in message:
                self.events.append(message)
        raise RRCacheError(f"DevTools {method} got no answer in {self.timeout} s", "chromium")

    def wait_for(self, method: str, since: int = 0) -> dict:
        """Wait for the event ``method`` (kept events from index ``since`` count)."""
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            for event in self.events[since:]:
                if event["method"] == method:
                    return event
            import websocket

            self._ws.settimeout(max(0.05, deadline - time.monotonic()))
            try:
                message = json.loads(self._ws.recv())
            except websocket.WebSocketTimeoutException:
                continue
            finally:
                self._ws.settimeout(self.timeout)
            if "method" in message:
                self.events.append(message)
        raise RRCacheError(f"no {method} within {self.timeout} s", "chromium")

    # ------------------------------------------------------------------ what a test uses
    def open(self, path_or_url, query: str = "") -> None:
        """Load a file (or URL), with ``query`` (``?size=64x48``) after it, and wait for its load
        event."""
        url = str(path_or_url)
        if "://" not in url:
            url = Path(url).resolve().as_uri()
        url += query
        self.url = url
        self._opened = getattr(self, "_opened", set()) | {url}
        mark = len(self.events)
        self.send("Page.navigate", url=url)
        self.wait_for("Page.loadEventFired", since=mark)

    def evaluate(self, expression: str):
        """The value of a JavaScript expression in the page (exceptions raise RRCacheError)."""
        result = self.send("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in result:
            raise RRCacheError(f"JavaScript error: {result['exceptionDetails'].get('text')} in {expression[:80]!r}",
                               "chromium")
        return result["result"].get("value")

    def mouse(self, kind: str, x: float, y: float) -> None:
        """``kind``: ``move`` or ``click`` at viewport position (x, y)."""
        if kind == "move":
            self.send("Input.dispatchMouseEvent", type="mouseMoved", x=x, y=y)
            return
        self.send("Input.dispatchMouseEvent", type="mouseMoved", x=x, y=y)
        for phase in ("mousePressed", "mouseReleased"):
            self.send("Input.dispatchMouseEvent", type=phase, x=x, y=y, button="left", clickCount=1)

    def screenshot(self, path, full_page: bool = False) -> Path:
        """Save a PNG of the viewport (or of the whole page) to ``path``."""
        params = {"format": "png"}
        if full_page:
            size = self.send("Page.getLayoutMetrics")["cssContentSize"]
            params.update(captureBeyondViewport=True,
                          clip={"x": 0, "y": 0, "width": size["width"], "height": size["height"], "scale": 1})
        data = base64.b64decode(self.send("Page.captureScreenshot", **params)["data"])
        from rrcache.atomic import write_bytes

        path = Path(path)
        write_bytes(path, data)
        return path

    def errors(self) -> list[str]:
        """Console errors, uncaught exceptions and error log entries so far."""
        out = []
        for event in self.events:
            method, params = event["method"], event.get("params", {})
            if method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
                out.append("console: " + " ".join(str(a.get("value", a.get("description", ""))) for a in params.get("args", [])))
            elif method == "Runtime.exceptionThrown":
                details = params.get("exceptionDetails", {})
                out.append("exception: " + str(details.get("exception", {}).get("description") or details.get("text")))
            elif method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
                out.append("log: " + params["entry"].get("text", ""))
        return out

    def requests(self) -> list[str]:
        """URLs the pages requested, other than ``data:`` URIs and the pages opened."""
        urls = [e["params"]["request"]["url"] for e in self.events if e["method"] == "Network.requestWillBeSent"]
        return [u for u in urls if not u.startswith("data:") and u not in getattr(self, "_opened", set())]

    # ------------------------------------------------------------------ shutting down
    def close(self) -> None:
        ws = getattr(self, "_ws", None)
        if ws is not None:
            try:
                ws.close()
            except Exception:  # the browser may be gone already
                pass
            self._ws = None
        if self._proc.poll() is None:
            self._proc.terminate()
            try:
                self._proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        self._log.close()
        shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self) -> "Chromium":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
