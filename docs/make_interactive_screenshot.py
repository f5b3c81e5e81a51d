"""Regenerate docs/interactive.png: notebooks/interactive.ipynb run in JupyterLab (headless
Chromium over DevTools, :mod:`rrcache.report.browser`), photographed with its live widget.

    python docs/make_interactive_screenshot.py [--profile DIR]

JupyterLab serves the notebook from a temporary folder on 127.0.0.1 (no token, this machine
only); the script runs all cells through JupyterLab's own command, waits for the widget's
images, and scrolls the widget into view. ``--profile`` reuses a demo profile folder instead of
making one (seconds). Needs the ``notebooks`` extra (jupyterlab) and Chromium.
"""
from __future__ import annotations

import argparse
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from rrcache.report.browser import Chromium  # noqa: E402


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait(browser, expression: str, timeout: float, what: str):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = browser.evaluate(expression)
        if value:
            return value
        time.sleep(0.5)
    raise SystemExit(f"timed out waiting for {what}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", help="an existing demo profile folder to copy")
    parser.add_argument("--out", default=str(ROOT / "docs" / "interactive.png"))
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="rrcache-lab-"))
    shutil.copy(ROOT / "notebooks" / "interactive.ipynb", work)
    if args.profile:
        shutil.copytree(args.profile, work / "demo.rrprofile")
    port = _free_port()
    env = dict(os.environ, LP_NUM_THREADS=os.environ.get("LP_NUM_THREADS", "1"), JUPYTER_CONFIG_DIR=str(work / ".cfg"))
    lab = subprocess.Popen([sys.executable, "-m", "jupyterlab", "--no-browser", f"--port={port}", "--ip=127.0.0.1",
                            "--allow-root", "--IdentityProvider.token=", "--ServerApp.password=", "--LabApp.expose_app_in_browser=True",
                            f"--ServerApp.root_dir={work}", "--ServerApp.disable_check_xsrf=True",
                            "--LabApp.news_url=", "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate"],
                           env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                urllib.request.urlopen(f"http://127.0.0.1:{port}/api", timeout=2)
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise SystemExit("JupyterLab did not start")
                time.sleep(0.5)
        with Chromium(width=1280, height=1180, timeout=120) as browser:
            browser.open(f"http://127.0.0.1:{port}/lab/tree/interactive.ipynb")
            _wait(browser, "!!(window.jupyterapp && document.querySelector('.jp-Notebook .jp-Cell'))", 90, "the notebook")
            panel = ("Array.from(window.jupyterapp.shell.widgets('main'))"
                     ".find(function (w) { return w.sessionContext; })")
            browser.evaluate(f"window.jupyterapp.shell.activateById({panel}.id)")
            _wait(browser, f"!!({panel}.sessionContext.session && {panel}.sessionContext.session.kernel)", 90,
                  "the kernel")
            time.sleep(2)
            browser.evaluate("window.jupyterapp.commands.execute('notebook:run-all-cells')")
            _wait(browser, "document.querySelectorAll('.widget-slider').length > 0 &&"
                           " document.querySelectorAll('.jp-OutputArea-output img').length >= 4", 300, "the widget")
            # the slider snaps a value set from code to its step and sends it back: the kernel then
            # re-selects once more; wait until that is drawn too
            for _ in range(2):
                _wait(browser, f"{panel}.sessionContext.session.kernel.status === 'idle' &&"
                               " !document.body.innerText.includes('rendering and measuring')", 300,
                      "the kernel to finish")
                time.sleep(3)
            browser.evaluate("Array.from(document.querySelectorAll('.jp-toast-button, .Toastify button'))"
                             ".filter(function (b) { return b.textContent.trim() === 'No'; })"
                             ".forEach(function (b) { b.click(); })")
            browser.evaluate("window.jupyterapp.shell.leftCollapsed ||"
                             " window.jupyterapp.commands.execute('application:toggle-left-area')")
            time.sleep(1)
            browser.evaluate("(function(){var cells=document.querySelectorAll('.jp-Notebook .jp-Cell');"
                             "cells[1].scrollIntoView({block:'start'});})()")
            time.sleep(1.5)
            out = browser.screenshot(args.out)
            print(f"wrote {out}; console errors: {browser.errors() or 'none'}")
    finally:
        lab.terminate()
        lab.wait(timeout=20)
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
