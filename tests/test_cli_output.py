"""Output that reads well anywhere: progress off a terminal (a line every interval while a step
runs, an ETA that says "estimating" until it is steady), tables whole on a pipe, plain units."""
from __future__ import annotations

import io
import json
import os
import subprocess
import sys
from pathlib import Path

from rich.console import Console

from rrcache.cli.progress import Eta, Reporter
from rrcache.cli.tables import TextTable

ROOT = Path(__file__).resolve().parent.parent


def test_a_long_step_prints_a_line_every_interval_off_a_terminal():
    out = io.StringIO()
    ticks = iter([0.0] + [float(t) for t in range(1, 200)])
    with Reporter(Console(file=out, force_terminal=False), clock=ticks.__next__, interval=10.0) as rep:
        for done in range(1, 100):
            rep.update("rendering", done, 150)
    lines = out.getvalue().strip().splitlines()
    # one line about every 10 s while the step runs, then the step's own line
    assert 8 <= len(lines) <= 11, lines
    assert all(": " in line and "/150" in line for line in lines)
    assert lines[0].endswith("(ETA estimating)")  # 10 s in: too early to say
    assert "ETA 5" in lines[-2] or "ETA 4" in lines[-2] or "ETA 6" in lines[-2], lines[-2]  # a steady 1 frame/s


def test_the_eta_waits_for_a_steady_rate():
    eta = Eta()
    # a fast start (references at another rate), then the steady work: never a wild guess
    shown = [eta.update(t, done, 1000) for t, done in [(1, 100), (5, 110), (20, 130), (40, 170), (60, 210)]]
    assert shown[:3] == [None, None, None]
    steady = [eta.update(60 + 20 * k, 210 + 40 * k, 1000) for k in range(1, 8)]
    assert steady[-1] is not None and abs(steady[-1] - (1000 - 490) / 2.0) < 0.3 * (1000 - 490) / 2.0


def test_tables_are_whole_off_a_terminal():
    table = TextTable("t", [("node", "left"), ("value", "right")])
    long_text = "sum + amplitude * abs(noise(p * frequency + vec3(1.7, 9.2, 3.1))) * 0.5 + 0.25 * grain"
    table.add_row("n2442: " + long_text, "1.23")
    out = io.StringIO()
    table.print(Console(file=out, force_terminal=False, width=40))
    assert long_text in out.getvalue() and "…" not in out.getvalue()


def test_render_on_a_pipe_prints_progress_and_a_whole_plain_table(tmp_path):
    from rrcache.profiler.demo import DEMO_SESSION, DEMO_SHADER

    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""), COLUMNS="60")
    done = subprocess.run([sys.executable, "-m", "rrcache", "render", str(DEMO_SHADER), str(DEMO_SESSION),
                           "--frames", "4"], capture_output=True, text=True, env=env, timeout=300, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "rendering: done (4/4)" in done.stderr
    out = done.stdout
    assert "┃" not in out and "│" not in out and "…" not in out  # plain text, nothing cut
    header = next(line for line in out.splitlines() if line.startswith("frame"))
    assert "covered pixels" in header and "ms" in header
    assert str(DEMO_SESSION) in out  # the title whole, though longer than COLUMNS
