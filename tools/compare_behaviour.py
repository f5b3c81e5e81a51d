"""Dump and compare what two versions of rrcache produce: node tables, emitted passes and the
shipped selections of a resumed profile (the successor of ``tools/compare_node_tables.py``).

    python tools/compare_behaviour.py dump ROOT OUT [--inputs DIR] [--profile DIR] [--train] [--quick]
    python tools/compare_behaviour.py compare DUMP_A DUMP_B [--ignore KEY ...]
    python tools/compare_behaviour.py make-profile ROOT OUT [--inputs DIR]

``dump`` runs the command line of the rrcache checkout ``ROOT`` (``PYTHONPATH=ROOT``, in process,
one interpreter) over the shaders of ``--inputs`` (a folder holding ``shaders/``, ``sessions/`` and
``tests/corpus/``; default: the current folder) and writes ``OUT/<shader>.json``:

- the node table (``rrcache nodes SHADER --session S --all --json``) with the shader's session
  (the bundled shaders with the session their scene uses, the corpus shaders with their own
  ``name.json`` or ``default_session.json``);
- the emitted passes (``rrcache instance``: every file it writes, and its message or error) of the
  two costliest listed nodes in every algorithm the table allows them, the two costliest nodes as a
  set (three-pass and two-pass), the costliest node with adaptive refresh, and every estimator
  amortized (blend, m = N/4; slots at the largest m that fits; slots in 8 bits where the terms'
  range is known).

With ``--train``, two small scenes (the demo scene and the amortization tests' scene) are profiled
afresh with settings that make what is trained independent of timing (a budget nothing reaches, no
minimum gain, a fixed algorithm, no validation), and ``OUT/training.json`` gets what the error runs
measured: every node error run and frame, every estimator error run, the trained sets' errors (the
sets trained depend on the timing models: only the sets both dumps trained are compared).

With ``--profile DIR`` (a profile folder made by ``make-profile``), a copy of it is resumed with the
same command line (every run is in its store, so nothing is measured and the result is
deterministic) and ``OUT/profile.json`` gets its selections, sets and estimators (the run's times
and counters left out), the files of ``optimized/`` and ``rrcache select --json`` at a few levels.

``compare`` prints one line per dumped item (``same``/``DIFF``, with the first differing keys) and
exits 1 when any differ. Use it to check that a refactoring changes no output.

Every run of a ``ROOT`` is ``python -P`` (from Python 3.11): neither the current folder (``-m``) nor the
driver's folder is put before ``PYTHONPATH``, so a run from inside a checkout cannot import that
checkout for both sides; the driver (and make-profile, beforehand) exits 2 when the ``rrcache`` it
imported is not ``ROOT``'s.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

#: the bundled shaders and the sessions their scenes use
SCENES = {
    "ambient_occlusion.glsl": "chess.json",
    "cheap_stripes.glsl": "cheap.json",
    "glslviewer_basic.glsl": "marble.json",
    "many_lights.glsl": "lights.json",
    "marble.glsl": "marble.json",
    "pcf_shadows.glsl": "temple.json",
    "sdf_material.glsl": "sdf.json",
    "trashcan.glsl": "trashcan.json",
}
#: the demo profile's command line (rrcache.profiler.demo.DEMO_SETTINGS)
DEMO_ARGS = ["--periods", "2,4,8,16", "--timing-frames", "6", "--timing-periods", "2,16", "--budget", "8"]
DEMO_SHADER, DEMO_SESSION = "rrcache/profiler/demo/marbled_sphere.glsl", "rrcache/profiler/demo/marbled_sphere.json"
#: profile.json keys that say how long a run took or how often it ran, not what it chose
VOLATILE = {"run_wall_s", "precompute_s", "invocations", "counts", "training_wall_s", "path", "shader", "session",
            "vertex", "plots", "trained_s", "created", "rrcache_version"}

_DRIVER = r'''
import contextlib, io, json, os, sys, tempfile, traceback
from pathlib import Path
import rrcache
_job = json.loads(sys.argv[1])
if not os.path.realpath(rrcache.__file__).startswith(os.path.join(os.path.realpath(_job["root"]), "rrcache", "")):
    print(f"{_job['root']}: imported rrcache from {rrcache.__file__}, not from this root", file=sys.stderr)
    sys.exit(2)
from rrcache.cli import cli

def run(args):
    out, err = io.StringIO(), io.StringIO()
    code = 0
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            cli.main(args, prog_name="rrcache", standalone_mode=False)
        except SystemExit as e:
            code = e.code if isinstance(e.code, int) else 1
        except Exception as e:  # an error the CLI would print: kept as its message
            code = 2
            err.write(f"{type(e).__name__}: {e}")
    return code, out.getvalue(), err.getvalue()

def files(folder):
    return {p.name: p.read_text() for p in sorted(Path(folder).iterdir()) if p.is_file()}

def instance(shader, session, extra):
    with tempfile.TemporaryDirectory() as tmp:
        code, out, err = run(["instance", shader, "--session", session, "--out", tmp, *extra])
        written = files(tmp) if code == 0 else {}
        # the message names the temporary folder: keep it out
        return {"args": extra, "code": code, "stdout": out.replace(tmp, "OUT"), "stderr": err.replace(tmp, "OUT"),
                "files": written}

def dump_shader(shader, session, quick):
    code, out, err = run(["nodes", shader, "--session", session, "--all", "--json"])
    try:
        table = json.loads(out)
    except ValueError:
        table = out
    record = {"shader": shader, "session": session, "nodes": {"code": code, "table": table, "stderr": err}}
    variants = []
    nodes = sorted(table.get("nodes", []), key=lambda n: (-n["cost"], n["id"])) if isinstance(table, dict) else []
    top = nodes[:2]
    for n in top:
        for algorithm in n.get("algorithms", []):
            variants.append(instance(shader, session, ["--node", n["id"], "--period", "8", "--algorithm", algorithm]))
            if quick:
                break
    if len(top) == 2:
        for algorithm in ("three-pass", "two-pass"):
            variants.append(instance(shader, session, ["--node", top[0]["id"], "--period", "50", "--node",
                                                       top[1]["id"], "--period", "4", "--algorithm", algorithm]))
    if top:
        variants.append(instance(shader, session, ["--node", top[0]["id"], "--period", "100", "--adaptive", "0.01",
                                                    "--fast-period", "4"]))
    for est in (table.get("estimators") or []) if isinstance(table, dict) else []:
        n = int(est.get("samples", 0))
        comps = int(est.get("components", 1) or 1)
        m = max(1, n // 4)
        variants.append(instance(shader, session, ["--estimator", est["id"], "--samples", str(m), "--lambda", "0.6"]))
        fits = [k for k in range(1, n) if n % k == 0 and (n // k) * comps <= 4]
        if fits:
            variants.append(instance(shader, session, ["--estimator", est["id"], "--samples", str(fits[-1]),
                                                        "--lambda", "0.6", "--history", "slots"]))
            if est.get("term_range") is not None:
                variants.append(instance(shader, session, ["--estimator", est["id"], "--samples", str(fits[-1]),
                                                            "--lambda", "0.6", "--history", "slots",
                                                            "--payload", "u8", "--filter", "catmull-rom-y"]))
    record["variants"] = variants
    return record

def dump_profile(folder, args, volatile):
    code, out, err = run(["profile", *args, "--out", folder, "--quiet"])
    record = {"profile": {"code": code, "stderr": err}}
    path = Path(folder) / "profile.json"
    if path.exists():
        doc = json.loads(path.read_text())
        def clean(x):
            if isinstance(x, dict):
                return {k: clean(v) for k, v in x.items() if k not in volatile}
            if isinstance(x, list):
                return [clean(v) for v in x]
            return x
        record["document"] = clean(doc)
    opt = Path(folder) / "optimized"
    record["optimized"] = {d.name: files(d) for d in sorted(opt.iterdir())} if opt.exists() else {}
    for level in ("45", "40", "35", "30", "25"):
        record[f"select --min-psnr {level}"] = run(["select", folder, "--min-psnr", level, "--json"])
    for level in ("0.001", "0.01", "0.05"):
        record[f"select --max-error {level}"] = run(["select", folder, "--max-error", level, "--json"])
    return record

TRAIN_ARGS = ["--periods", "2,4", "--frames", "8", "--timing-frames", "3", "--timing-periods", "2,4",
              "--budget", "100000", "--min-gain", "0", "--algorithm", "three-pass", "--no-validate", "--sets", "2",
              "--min-saving", "0.5", "--quiet"]

def dump_training(scenes):
    import sqlite3
    out = {}
    for name, shader, session in scenes:
        with tempfile.TemporaryDirectory() as tmp:
            code, _, err = run(["profile", shader, session, *TRAIN_ARGS, "--out", tmp])
            rec = {"code": code, "stderr": err if code else ""}
            db = Path(tmp) / "profile.sqlite"
            if db.exists():
                conn = sqlite3.connect(str(db))
                q = lambda sql: [list(r) for r in conn.execute(sql)]
                tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type='table'")}
                rec["error_run"] = q("SELECT node, period, mean_error, psnr, hit_rate, hits, misses, covered, frames "
                                     "FROM error_run ORDER BY node, period")
                rec["error_frame"] = q("SELECT node, period, frame, mean_error, psnr, hits, misses, covered, left_out "
                                       "FROM error_frame ORDER BY node, period, frame")
                rec["reference_frame"] = q("SELECT frame, covered FROM reference_frame ORDER BY frame")
                if "amortize_run" in tables:
                    cols = [c[1] for c in conn.execute("PRAGMA table_info(amortize_run)")]
                    hist = "history" if "history" in cols else "'blend'"
                    rec["amortize_error"] = q(f"SELECT estimator, {hist}, samples, blend, mean_error, psnr, hit_rate, "
                                              "hits, misses FROM amortize_run WHERE kind = 'error' "
                                              "ORDER BY estimator, 2, samples, blend")
                if not rec.get("amortize_error"):  # (a store without estimators may lack the table)
                    rec.pop("amortize_error", None)
                if "set_run" in tables:
                    sets = [json.loads(r[0]) for r in conn.execute("SELECT record FROM set_run")]
                else:
                    raw = dict(conn.execute("SELECT key, value FROM meta")).get("sets")
                    sets = json.loads(raw) if raw else []
                rec["sets"] = {"+".join(f"{n}:{p}" for n, p in zip(d["nodes"], d["periods"])):
                               [d.get("trained_error"), d.get("trained_psnr"), d.get("trained_hit_rates")]
                               for d in sets if d.get("trained")}
                conn.close()
            out[name] = rec
            print("trained", name, flush=True)
    return out

if __name__ == "__main__":
    job = _job
    out = Path(job["out"])
    out.mkdir(parents=True, exist_ok=True)
    for shader, session in job["shaders"]:
        record = dump_shader(shader, session, job["quick"])
        name = shader.replace("/", "__")
        (out / f"{name}.json").write_text(json.dumps(record, indent=1, sort_keys=True))
        print("dumped", shader, flush=True)
    if job.get("train"):
        (out / "training.json").write_text(json.dumps(dump_training(job["train"]), indent=1, sort_keys=True))
    if job.get("profile"):
        record = dump_profile(job["profile"], job["profile_args"], set(job["volatile"]))
        (out / "profile.json").write_text(json.dumps(record, indent=1, sort_keys=True))
        print("dumped the profile", flush=True)
'''


def _shaders(inputs: Path) -> list[tuple[str, str]]:
    out = [(f"shaders/{name}", f"sessions/{session}") for name, session in SCENES.items()
           if (inputs / "shaders" / name).exists()]
    for path in sorted((inputs / "tests" / "corpus").glob("*.glsl")):
        own = path.with_suffix(".json")
        session = own if own.exists() else path.parent / "default_session.json"
        out.append((str(path.relative_to(inputs)), str(session.relative_to(inputs))))
    return out


def _python(root: str) -> tuple[list[str], dict]:
    """The interpreter's command line and environment that import ``root``'s rrcache only."""
    safe = ["-P"] if sys.version_info >= (3, 11) else []
    return [sys.executable, *safe], dict(os.environ, PYTHONPATH=os.path.abspath(root))


def _imports_its_own(root: str, cwd: Path) -> bool:
    """Whether ``python -m rrcache`` started in ``cwd`` imports ``root``'s rrcache (``-c`` puts the
    current folder first as ``-m`` does)."""
    python, env = _python(root)
    p = subprocess.run([*python, "-c", "import os, rrcache; print(os.path.realpath(rrcache.__file__))"],
                       capture_output=True, text=True, env=env, cwd=cwd)
    if p.stdout.strip().startswith(os.path.join(os.path.realpath(root), "rrcache", "")):
        return True
    print(f"{root}: run from {cwd}, rrcache is imported from {p.stdout.strip() or p.stderr.strip()}, "
          "not from this root", file=sys.stderr)
    return False


def _run_driver(root: str, inputs: Path, job: dict) -> int:
    python, env = _python(root)
    folder = tempfile.mkdtemp(prefix="rrcache-driver-")
    driver = Path(folder) / "driver.py"
    driver.write_text(_DRIVER)
    try:
        return subprocess.run([*python, str(driver), json.dumps(dict(job, root=os.path.abspath(root)))],
                              cwd=inputs, env=env).returncode
    finally:
        shutil.rmtree(folder, ignore_errors=True)


#: the amortization tests' scene (tests/test_profile_amortize.py at 14ed2e0): a soft light summed
#: over 8 terms in a loop (an estimator) on a torus, 64×64, 12 frames
AMORTIZE_SHADER = '#version 330\nin vec4 v_position;\nin vec3 v_normal;\nin vec3 v_objectPosition;\nuniform vec3 u_light;\nuniform float u_scale;\nout vec4 fragColor;\n\nfloat wave(vec3 p, float f) {\n    return sin(p.x * f + 1.3 * cos(p.y * f)) * cos(p.z * f * 0.7 + sin(p.x * f * 1.9));\n}\n\nvoid main() {\n    vec3 p = v_objectPosition * u_scale;\n    vec3 nrm = normalize(v_normal);\n    vec3 l = normalize(u_light - v_position.xyz);\n    float shade = 0.0;\n    for (int i = 0; i < 8; i++) {\n        vec3 d = normalize(l + 0.35 * vec3(cos(float(i) * 2.4), sin(float(i) * 2.4), 0.5 * wave(p, 1.0 + float(i))));\n        shade += max(dot(nrm, d), 0.0) * (0.6 + 0.4 * wave(p, 2.0 + 0.3 * float(i)));\n    }\n    fragColor = vec4(vec3(0.9, 0.8, 0.6) * (0.2 + 0.1 * shade), 1.0);\n}\n'
AMORTIZE_SESSION = {"rrcache_session": 1, "resolution": [64, 64], "frames": 12, "fps": 30, "camera": {"fov": 45, "near": 0.1, "far": 50, "keyframes": [{"frame": 0, "eye": [0, 0.5, 3.2], "target": [0, 0, 0], "up": [0, 1, 0]}, {"frame": 11, "eye": [1.2, 0.6, 2.9], "target": [0, 0, 0], "up": [0, 1, 0]}]}, "light": {"color": [1, 1, 1], "orbit": {"center": [0, 0, 0], "radius": 4, "height": 3, "degrees_per_frame": 3}}, "objects": [{"procedural": {"type": "icosphere", "radius": 1.0, "subdivisions": 3}}], "uniforms": {"u_scale": 3.0}}


def _train_scenes(inputs: Path, tmp: str) -> list:
    """The demo scene, and the amortization tests' scene (written into ``tmp``)."""
    shader, session = Path(tmp) / "soft.frag", Path(tmp) / "orbit.json"
    shader.write_text(AMORTIZE_SHADER)
    session.write_text(json.dumps(AMORTIZE_SESSION))
    return [("demo", DEMO_SHADER, DEMO_SESSION), ("amortize", str(shader), str(session))]


def dump(root: str, out: str, inputs: str = ".", profile: str | None = None, quick: bool = False,
         train: bool = False, no_shaders: bool = False) -> int:
    inputs_path = Path(inputs).resolve()
    job = {"out": os.path.abspath(out), "shaders": [] if no_shaders else _shaders(inputs_path), "quick": quick,
           "volatile": sorted(VOLATILE)}
    tmp = tempfile.mkdtemp(prefix="rrcache-compare-")
    if train:
        job["train"] = _train_scenes(inputs_path, tmp)
    if profile:
        folder = Path(tmp) / "demo.rrprofile"
        shutil.copytree(profile, folder)
        job["profile"] = str(folder)
        job["profile_args"] = [DEMO_SHADER, DEMO_SESSION, *DEMO_ARGS]
    try:
        return _run_driver(root, inputs_path, job)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def make_profile(root: str, out: str, inputs: str = ".") -> int:
    """Profile the demo scene with ``ROOT``'s rrcache into ``OUT`` (measured: run it once)."""
    if not _imports_its_own(root, Path(inputs).resolve()):
        return 2
    python, env = _python(root)
    return subprocess.run([*python, "-m", "rrcache", "profile", DEMO_SHADER, DEMO_SESSION, *DEMO_ARGS,
                           "--out", os.path.abspath(out)], cwd=Path(inputs).resolve(), env=env).returncode


def _diff(a, b, path="", found=None, limit=5):
    found = [] if found is None else found
    if len(found) >= limit:
        return found
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                found.append(f"{path}/{k}: only in {'A' if k in a else 'B'}")
            else:
                _diff(a[k], b[k], f"{path}/{k}", found, limit)
    elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b)):
            _diff(x, y, f"{path}[{i}]", found, limit)
    elif a != b:
        found.append(f"{path}: {str(a)[:80]!r} != {str(b)[:80]!r}")
    return found


def _drop(x, keys):
    if isinstance(x, dict):
        return {k: _drop(v, keys) for k, v in x.items() if k not in keys}
    if isinstance(x, list):
        return [_drop(v, keys) for v in x]
    return x


def compare(a: str, b: str, ignore=()) -> int:
    """Compare two dumps (``ignore``: keys left out anywhere, e.g. a field added on purpose)."""
    names = sorted({p.name for p in Path(a).glob("*.json")} | {p.name for p in Path(b).glob("*.json")})
    diffs = 0
    for name in names:
        pa, pb = Path(a) / name, Path(b) / name
        if not pa.exists() or not pb.exists():
            print(f"DIFF {name}: only in {'A' if pa.exists() else 'B'}")
            diffs += 1
            continue
        x, y = _drop(json.loads(pa.read_text()), set(ignore)), _drop(json.loads(pb.read_text()), set(ignore))
        if name == "training.json":  # the sets trained depend on timing: compare those both trained
            for scene in set(x) & set(y):
                a, b = x[scene].get("sets", {}), y[scene].get("sets", {})
                common = set(a) & set(b)
                x[scene]["sets"], y[scene]["sets"] = {k: a[k] for k in common}, {k: b[k] for k in common}
        if x == y:
            count = len(x.get("variants", ())) if isinstance(x, dict) else 0
            print(f"same {name}" + (f" ({count} variants)" if count else ""))
        else:
            diffs += 1
            print(f"DIFF {name}")
            for line in _diff(x, y):
                print("    " + line)
    print(f"{len(names)} dumps compared, {diffs} differences")
    return 1 if diffs else 0


def main(argv: list[str]) -> int:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    sub = parser.add_subparsers(dest="what", required=True)
    d = sub.add_parser("dump")
    d.add_argument("root")
    d.add_argument("out")
    d.add_argument("--inputs", default=".")
    d.add_argument("--profile", default=None)
    d.add_argument("--quick", action="store_true", help="one algorithm per node")
    d.add_argument("--train", action="store_true", help="profile two small scenes afresh and dump their error runs")
    d.add_argument("--no-shaders", action="store_true", help="leave out the node tables and passes")
    c = sub.add_parser("compare")
    c.add_argument("a")
    c.add_argument("b")
    c.add_argument("--ignore", action="append", default=[], metavar="KEY",
                   help="leave this key out anywhere (a field added on purpose); repeatable")
    m = sub.add_parser("make-profile")
    m.add_argument("root")
    m.add_argument("out")
    m.add_argument("--inputs", default=".")
    args = parser.parse_args(argv)
    if args.what == "dump":
        return dump(args.root, args.out, args.inputs, args.profile, args.quick, args.train, args.no_shaders)
    if args.what == "compare":
        return compare(args.a, args.b, args.ignore)
    return make_profile(args.root, args.out, args.inputs)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
