"""One store, one writer (issue 16): the lock on a profile folder, with real processes; and the
store's rows checked when read (a hit rate of 7, a negative error, NaN are refused, naming the
row and the column)."""
from __future__ import annotations

import math
import os
import signal
import sqlite3
import subprocess
import sys
import time

import pytest

from rrcache.errors import RRCacheError
from rrcache.profiler.lock import LOCK_NAME, StoreLock
from rrcache.profiles.store import ErrorFrame, ErrorRun, ProfileStore, StoreKey, TimingFrame, read_store
from safety_cli import QUICK_PROFILE, env, one_error_line, rrcache, write_case

AREA = "safety: one store, one writer; stored rows checked"
KEY = StoreKey("s" * 64, "t" * 64, "u" * 64, "0.0-test", "{}")

_HOLDER = """
import sys, time
from rrcache.profiler.lock import StoreLock
lock = StoreLock.acquire(sys.argv[1])
print("held", flush=True)
time.sleep(float(sys.argv[2]))
"""


def _holder(lock_path, seconds=120.0):
    """A real process holding the folder's lock (as a running ``rrcache profile`` does)."""
    proc = subprocess.Popen([sys.executable, "-c", _HOLDER, str(lock_path), str(seconds)], env=env(),
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "held"
    return proc


def test_second_profile_is_told_who_holds_the_folder(tmp_path, stability_case):
    write_case(tmp_path)
    holder = _holder(tmp_path / "out" / LOCK_NAME)
    case = stability_case("second rrcache profile on the same --out", AREA,
                          "a live process holds out/profile.lock; rrcache profile --out out")
    try:
        code, _, lines = rrcache(tmp_path, "profile", "scene.frag", "scene.json", "--out", "out", *QUICK_PROFILE)
        line = one_error_line(code, lines)
    finally:
        holder.kill()
        holder.wait()
    case.observe(exit=code, stderr=line.replace(str(tmp_path), "TMP").replace(str(holder.pid), "PID"))
    assert f"pid {holder.pid}" in line and "--wait" in line
    assert not (tmp_path / "out" / "profile.sqlite").exists()  # refused before the store was touched


def test_killed_holder_leaves_no_stale_lock(tmp_path, stability_case):
    write_case(tmp_path)
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "rrcache", "profile", "scene.frag", "scene.json", "--out", "out",
                             *QUICK_PROFILE], cwd=tmp_path, env=env(),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    lock = out / LOCK_NAME
    deadline = time.monotonic() + 240
    while not (lock.exists() and lock.read_text().startswith("pid")):
        assert proc.poll() is None and time.monotonic() < deadline, "profile never took the lock"
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    case = stability_case("rrcache profile killed (SIGKILL) while holding the lock", AREA,
                          "SIGKILL once profile.lock names the run; then the lock is taken again")
    with StoreLock.acquire(lock) as again:  # without wait: raises if the dead run still held it
        taken = again.fd is not None
    code, _, lines = rrcache(tmp_path, "profile", "scene.frag", "scene.json", "--out", "out", *QUICK_PROFILE)
    case.observe(killed_exit=proc.returncode, lock_file_left=lock.exists(), relocked=taken,
                 next_profile_exit=code)
    assert proc.returncode == -signal.SIGKILL and taken
    assert code == 0, lines


def test_wait_takes_the_lock_when_the_holder_ends(tmp_path, stability_case):
    lock = tmp_path / "out" / LOCK_NAME
    holder = _holder(lock, seconds=1.5)
    case = stability_case("--wait for the holder", AREA, "a process holds the lock for 1.5 s; acquire(wait=True)")
    with pytest.raises(RRCacheError):
        StoreLock.acquire(lock)
    with StoreLock.acquire(lock, wait=True) as mine:
        held = mine.fd is not None
    holder.wait()
    case.observe(held_after_wait=held, holder_exit=holder.returncode)
    assert held and holder.returncode == 0


# ----------------------------------------------------------------------------- stored rows

def _store(tmp_path):
    store = ProfileStore.open(tmp_path / "profile.sqlite", KEY)
    store.begin_run()
    store.add_error_run(ErrorRun("n3", 8, 0.01, 40.0, 0.8, 80, 20, 100, 1, 0.5),
                        [ErrorFrame(1, 0.01, 40.0, 80, 20, 100)])
    store.add_timing_run("n3", 8, [TimingFrame(1, 80, 20, 1.5, 2.0)], 0.2)
    store.add_reference_timing([(1, 2.0, 100)])
    store.set_overhead("n3", (4, 4), 3, 0.3)
    return store


TAMPER = {
    "hit rate of 7": ("UPDATE error_run SET hit_rate = 7", "error_runs", "hit_rate = 7"),
    "negative error": ("UPDATE error_run SET mean_error = -0.5", "error_runs", "mean_error = -0.5"),
    "NaN error in a frame": ("UPDATE error_frame SET mean_error = 'nan'", "error_frames", "mean_error"),
    "negative frame time": ("UPDATE timing_frame SET ms = -3", "timing_frames", "ms = -3"),
    "text where a number belongs": ("UPDATE reference_timing SET ms = 'fast'", "reference_timing", "is not a number"),
    "negative hits": ("UPDATE error_run SET hits = -1", "error_runs", "hits = -1"),
    "infinite overhead": ("UPDATE overhead SET ms = 9e999", "overhead", "is infinite"),
}


@pytest.mark.parametrize("name", list(TAMPER), ids=lambda n: n.replace(" ", "-"))
def test_tampered_rows_are_refused(tmp_path, stability_case, name):
    sql, reader, expected = TAMPER[name]
    _store(tmp_path).close()
    with sqlite3.connect(tmp_path / "profile.sqlite") as conn:
        conn.execute(sql)
    case = stability_case(f"stored row: {name}", AREA, sql)
    # a run resuming on the store refuses it when it opens it (every row checked)...
    with pytest.raises(RRCacheError) as at_open:
        ProfileStore.open(tmp_path / "profile.sqlite", KEY)
    assert expected in str(at_open.value) and "--fresh" in str(at_open.value)
    # ...and a reader of the rows (a report, a test) refuses the row it reads
    store = read_store(tmp_path / "profile.sqlite")
    try:
        with pytest.raises(RRCacheError) as info:
            if reader == "error_frames":
                store.error_frames("n3", 8)
            elif reader == "timing_frames":
                store.timing_frames("n3")
            else:
                getattr(store, reader)()
    finally:
        store.close()
    msg = str(info.value)
    case.observe(error=msg.replace(str(tmp_path), "TMP"))
    assert expected in msg and "--fresh" in msg and "n3" in msg or "frame=1" in msg


def test_clean_rows_read_back(tmp_path):
    store = _store(tmp_path)
    try:
        (run,) = store.error_runs()
        assert run.hit_rate == 0.8 and math.isfinite(run.mean_error)
        assert store.overhead()["ms"] == 0.3
        assert store.timing_frames("n3")[8][0].ms == 1.5
    finally:
        store.close()


def test_tampered_store_through_profile_is_one_line(tmp_path, stability_case):
    """A real profile run, its store tampered with (hit rate 7), then the same command again: it
    resumes from the store and must refuse the row instead of fitting it."""
    write_case(tmp_path)
    code, _, lines = rrcache(tmp_path, "profile", "scene.frag", "scene.json", "--out", "out", *QUICK_PROFILE)
    assert code == 0, lines
    with sqlite3.connect(tmp_path / "out" / "profile.sqlite") as conn:
        conn.execute("UPDATE error_run SET hit_rate = 7 WHERE rowid = (SELECT MIN(rowid) FROM error_run)")
    case = stability_case("tampered store, resumed through rrcache profile", AREA,
                          "one error_run row's hit_rate set to 7; rrcache profile again")
    code, _, lines = rrcache(tmp_path, "profile", "scene.frag", "scene.json", "--out", "out", *QUICK_PROFILE)
    line = one_error_line(code, lines)
    case.observe(exit=code, stderr=line.replace(str(tmp_path), "TMP"))
    assert "hit_rate = 7" in line and "profile.sqlite" in line
