"""Shared pieces of the safety tests (issue 16): a tiny shader and session, and running the real
``python -m rrcache`` in a subprocess with this checkout's code."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

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


def rrcache(cwd, *args, stdout=subprocess.PIPE, timeout=300, **popen):
    """``python -m rrcache ARGS`` in ``cwd``: (exit code, stdout, the non-empty stderr lines)."""
    proc = subprocess.run([sys.executable, "-m", "rrcache", *map(str, args)], cwd=cwd, env=env(),
                          stdout=stdout, stderr=subprocess.PIPE, text=True, timeout=timeout, **popen)
    return proc.returncode, proc.stdout, [line for line in proc.stderr.splitlines() if line.strip()]


def one_error_line(code, lines) -> str:
    """The run failed cleanly: exit code 2, one line on stderr, no traceback."""
    assert code == 2, (code, lines)
    errors = [line for line in lines if not line.startswith(("warning:", "note:"))]
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


def rrcache_traced(cwd, *args, timeout=300, stdin=subprocess.DEVNULL):
    """``rrcache ARGS`` in ``cwd``, traced: (exit code, stdout, the non-empty stderr lines, the
    child's peak resident memory in MiB (its own ``wait4`` rusage), every path it opened).
    A run past ``timeout`` seconds is killed (a hang guard, not a timing)."""
    import tempfile
    import threading

    with tempfile.TemporaryDirectory(prefix="rrcache-traced-") as tmp:
        names = {k: os.path.join(tmp, k) for k in ("out", "err", "opens")}
        open(names["opens"], "w").close()
        with open(names["out"], "w") as out, open(names["err"], "w") as err:
            proc = subprocess.Popen([sys.executable, "-c", _TRACED, *map(str, args)], cwd=cwd, stdin=stdin,
                                    env={**env(), "RRCACHE_TEST_OPENS": names["opens"]}, stdout=out, stderr=err)
        timer = threading.Timer(timeout, proc.kill)
        timer.start()
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        finally:
            timer.cancel()
        proc.returncode = code = os.waitstatus_to_exitcode(status)
        assert code != -9, f"killed after {timeout} s: {args}"
        read = lambda k: open(names[k], encoding="utf-8", errors="replace").read()  # noqa: E731
        lines = [line for line in read("err").splitlines() if line.strip()]
        return code, read("out"), lines, usage.ru_maxrss / 1024, read("opens").splitlines()
