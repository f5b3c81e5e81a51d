"""Shared pieces of the safety tests (issue 16): a tiny shader and session, and running the real
``python -m rrcache`` in a subprocess with this checkout's code."""
from __future__ import annotations

import json
import os
import re
import sqlite3
import subprocess
import sys
from pathlib import Path

import pytest

from child import python_argv

ROOT = Path(__file__).resolve().parent.parent

SHADER = """#version 330
in vec3 v_normal;
uniform float u_time;
out vec4 c;
void main() {
  vec3 n = normalize(v_normal);
  float s = 0.0;
  for (int i = 0; i < 8; i++) { s += sin(n.x * float(i) + u_time) * cos(n.y * float(i)); }
  c = vec4(vec3(s * 0.1 + 0.5), 1.0);
}
"""

SESSION = {
    "rrcache_session": 1, "resolution": [32, 24], "frames": 6, "fps": 30,
    "camera": {"fov": 45, "near": 0.1, "far": 100,
               "keyframes": [{"frame": 0, "eye": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0]},
                             {"frame": 5, "eye": [1, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0]}]},
    "objects": [{"procedural": {"type": "icosphere", "subdivisions": 1}}],
}

#: the most memory (MiB) a command that refuses its input may take (measured: 44-118 MiB: the
#: interpreter, numpy and, for textures, OpenImageIO); reading a hostile input would take gigabytes
REFUSAL_PEAK_MIB = 300
#: the most memory (MiB) a command that renders or profiles this module's 32×24 scene may take
#: (GL through llvmpipe, the profile's plots and report)
RUN_PEAK_MIB = 1024

#: the smallest profile run: a few seconds on llvmpipe
QUICK_PROFILE = ["--budget", "3", "--periods", "2,4", "--timing-periods", "2", "--timing-frames", "2",
                 "--no-validate", "--algorithm", "three-pass", "--min-gain", "0"]


def session(**changes) -> dict:
    doc = json.loads(json.dumps(SESSION))
    doc.update(changes)
    return doc


def write_case(folder: Path, doc: dict | None = None, shader: str = SHADER, name: str = "scene") -> tuple[Path, Path]:
    folder.mkdir(parents=True, exist_ok=True)
    frag = folder / f"{name}.frag"
    frag.write_text(shader)
    sess = folder / f"{name}.json"
    sess.write_text(json.dumps(doc if doc is not None else SESSION))
    return frag, sess


def env() -> dict:
    return {**os.environ, "LP_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}


def rrcache(cwd, *args, stdout=subprocess.PIPE, timeout=300, file_size=None):
    """``python -m rrcache ARGS`` in ``cwd``: (exit code, stdout, the non-empty stderr lines);
    ``file_size``: a limit in bytes on the files it writes (tests/child.py)."""
    proc = subprocess.run(python_argv(["-m", "rrcache", *args], file_size=file_size), cwd=cwd, env=env(),
                          stdout=stdout, stderr=subprocess.PIPE, text=True, timeout=timeout)
    return proc.returncode, proc.stdout, [line for line in proc.stderr.splitlines() if line.strip()]


#: a progress line off a terminal (rrcache/cli/progress.py): a resumed profile that still had work
#: when it was refused (its first run's budget ran out early on a loaded machine) prints some
PROGRESS_LINE = re.compile(r"^\[\s*\d+(\.\d+)? s\] ")


def one_error_line(code, lines) -> str:
    """The run failed cleanly: exit code 2, one line on stderr besides warnings, notes and
    progress, no traceback."""
    assert code == 2, (code, lines)
    errors = [line for line in lines if not line.startswith(("warning:", "note:")) and not PROGRESS_LINE.match(line)]
    assert len(errors) == 1, lines
    assert "Traceback" not in "\n".join(lines)
    assert errors[0].startswith("rrcache: error: "), errors[0]
    return errors[0]


def tree(folder: Path) -> dict:
    """Every file under ``folder`` with its size and modification time."""
    out = {}
    for path in sorted(Path(folder).rglob("*")):
        if path.is_file() or path.is_symlink():
            st = path.lstat()
            out[str(path)] = (st.st_size, st.st_mtime_ns)
    return out


#: ``python -c`` of :func:`rrcache_traced`: rrcache's command line with an audit hook that logs
#: every path the process opens through Python (``open()``, ``os.open``: every file rrcache
#: reads or writes goes through them; C libraries get ``/proc/self/fd/N``)
_TRACED = """
import os, sys
log = open(os.environ["RRCACHE_TEST_OPENS"], "a", encoding="utf-8", errors="replace")
def hook(event, args):
    if event == "open" and args and isinstance(args[0], (str, bytes)):
        log.write(os.fsdecode(args[0]).replace("\\n", " ") + "\\n")
        log.flush()
sys.addaudithook(hook)
from rrcache.cli import main
main(sys.argv[1:])
"""


#: a small launcher between the test and the traced command: the kernel starts a child's peak
#: memory count from its parent's resident size at the fork, so the command is forked from this
#: fresh interpreter (tens of MiB), not from the test process, and its own peak is what is measured
_LAUNCH = """
import os, signal, sys
usage_file, argv = sys.argv[1], sys.argv[2:]
pid = os.fork()
if pid == 0:
    os.execv(sys.executable, [sys.executable, *argv])
for sig in (signal.SIGTERM, signal.SIGINT):  # a signal to the launcher is the command's
    signal.signal(sig, lambda number, _frame: os.kill(pid, number))
_, status, usage = os.wait4(pid, 0)
with open(usage_file, "w") as f:
    f.write(str(usage.ru_maxrss))
sys.exit(os.waitstatus_to_exitcode(status) % 256)
"""


def launched(usage_file, *args) -> list:
    """The command line running ``python -m rrcache ARGS`` under the launcher, which writes the
    command's peak resident memory (KiB) to ``usage_file`` when it ends and passes SIGTERM and
    SIGINT on to it (for a test that starts it with ``Popen``; :func:`peak_mib` reads it)."""
    return [sys.executable, "-c", _LAUNCH, str(usage_file), "-m", "rrcache", *map(str, args)]


def peak_mib(usage_file) -> float:
    return int(open(usage_file).read()) / 1024


def rrcache_traced(cwd, *args, timeout=300, stdin=subprocess.DEVNULL):
    """``rrcache ARGS`` in ``cwd``, traced: (exit code, stdout, the non-empty stderr lines, the
    command's peak resident memory in MiB (its own ``wait4`` rusage, forked from a small
    launcher), every path it opened). A run past ``timeout`` seconds is killed (a hang guard,
    not a timing)."""
    import tempfile

    with tempfile.TemporaryDirectory(prefix="rrcache-traced-") as tmp:
        names = {k: os.path.join(tmp, k) for k in ("out", "err", "opens", "usage")}
        open(names["opens"], "w").close()
        with open(names["out"], "w") as out, open(names["err"], "w") as err:
            proc = subprocess.run([sys.executable, "-c", _LAUNCH, names["usage"], "-c", _TRACED, *map(str, args)],
                                  cwd=cwd, stdin=stdin, env={**env(), "RRCACHE_TEST_OPENS": names["opens"]},
                                  stdout=out, stderr=err, timeout=timeout)
        read = lambda k: open(names[k], encoding="utf-8", errors="replace").read()  # noqa: E731
        lines = [line for line in read("err").splitlines() if line.strip()]
        return proc.returncode, read("out"), lines, peak_mib(names["usage"]), read("opens").splitlines()


@pytest.fixture(scope="module")
def made_profile(tmp_path_factory):
    """A folder with ``scene.frag``, ``scene.json`` and ``p/``, their small profile (every
    selection the original at this size: seconds), made once per test module for its tests to
    copy."""
    folder = tmp_path_factory.mktemp("made")
    write_case(folder)
    code, _, lines = rrcache(folder, "profile", "scene.frag", "scene.json", "--out", "p", *QUICK_PROFILE)
    assert code == 0, lines
    return folder


def stored_error_runs(path) -> int:
    """The error runs the store at ``path`` holds now, read without waiting on its writer (0 while
    it is missing, being created or locked for a moment)."""
    if not Path(path).exists():
        return 0
    try:
        conn = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=0.2)
        try:
            return int(conn.execute("SELECT COUNT(*) FROM error_run").fetchone()[0])
        finally:
            conn.close()
    except sqlite3.Error:
        return 0
