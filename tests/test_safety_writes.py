"""The one rule for writing (issue 30, :mod:`rrcache.atomic`): outputs go only to regular files
inside the chosen folder, created without following links; an existing target that is not a
regular file is an error, never renamed over.

``rrcache report P --out /dev/null`` run as root once replaced the machine's ``/dev/null`` with a
regular file. These tests never touch the system's ``/dev``: every device node and FIFO is made
by the test inside its own temporary folder (``mknod`` needs root: without it the device cases
skip, the FIFO and directory cases still run). Links placed inside a profile folder point at files
and folders of the test's own ``outside`` folder, whose every file is checked unchanged after.
"""
from __future__ import annotations

import os
import shutil
import stat
import threading

import pytest

from rrcache.atomic import OutputFolder, write_text
from rrcache.errors import RRCacheError
from safety_cli import (QUICK_PROFILE, REFUSAL_PEAK_MIB, RUN_PEAK_MIB, made_profile, one_error_line,  # noqa: F401
                        rrcache_traced, tree)

AREA = "safety: the one rule for writing"


def _device(path, minor: int = 3) -> bool:
    """A private character device node with the numbers (1, ``minor``) of /dev/null (3) or
    /dev/full (7), made here; False without the privilege."""
    try:
        os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, minor))
        return True
    except (PermissionError, OSError):
        return False


@pytest.fixture
def case(made_profile, tmp_path):
    """A copy of the profile case in ``tmp_path/case`` and an ``outside`` folder with a file."""
    shutil.copytree(made_profile, tmp_path / "case", symlinks=True)
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "precious.txt").write_text("keep me\n")
    return tmp_path / "case", outside


# ----------------------------------------------------------------------------- in process

def test_a_target_that_is_not_a_regular_file_is_refused(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    os.mkfifo(out / "fifo.html")
    (out / "dir.html").mkdir()
    (tmp_path / "elsewhere.txt").write_text("x\n")
    os.symlink(tmp_path / "elsewhere.txt", out / "link.html")
    targets = {"fifo.html": "a FIFO \\(named pipe\\)", "dir.html": "a directory", "link.html": "a symbolic link"}
    if _device(out / "null.html"):
        targets["null.html"] = "a character device"
    for name, kind in targets.items():
        before = os.lstat(out / name)
        with pytest.raises(RRCacheError, match=f"exists and is {kind}, not a regular file"):
            write_text(out / name, "<html>")
        after = os.lstat(out / name)
        assert (after.st_mode, after.st_ino, after.st_rdev) == (before.st_mode, before.st_ino, before.st_rdev)
    assert (tmp_path / "elsewhere.txt").read_text() == "x\n"
    assert sorted(os.listdir(out)) == sorted(targets)  # no temporary file left behind


def test_files_are_written_whole_with_the_usual_mode(tmp_path):
    old = os.umask(0o027)
    try:
        path = write_text(tmp_path / "a" / "b.txt", "hello\n")
    finally:
        os.umask(old)
    assert open(path).read() == "hello\n"
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o640
    write_text(tmp_path / "a" / "b.txt", "again\n")  # a regular file is replaced
    assert open(path).read() == "again\n" and os.listdir(tmp_path / "a") == ["b.txt"]


def test_subfolders_are_opened_without_following_links(tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "keep.frag").write_text("keep\n")
    root = tmp_path / "p"
    root.mkdir()
    os.symlink(outside, root / "optimized")
    with OutputFolder(root) as folder:
        with pytest.raises(RRCacheError, match="exists and is a symbolic link, not a folder"):
            folder.folder("optimized")
        # a folder holding a link to a file elsewhere: remove_files leaves the link and its target
        with folder.folder("real") as real:
            os.symlink(outside / "keep.frag", root / "real" / "link.frag")
            real.write_text("pass.frag", "x\n")
            real.remove_files()
    assert os.listdir(root / "real") == ["link.frag"]
    assert (outside / "keep.frag").read_text() == "keep\n"


def test_writes_through_a_flipping_link_never_leave_the_folder(tmp_path):
    """A thread flips ``p/optimized`` between a folder and a link to ``outside`` while the main
    thread writes a selection's files into it, 300 times: nothing is ever written outside."""
    outside = tmp_path / "outside"
    outside.mkdir()
    root = tmp_path / "p"
    root.mkdir()
    stop = threading.Event()

    def flip():
        link, real = root / "optimized", root / "optimized.real"
        real.mkdir()
        while not stop.is_set():
            for make in (lambda: os.symlink(outside, link), lambda: os.rename(real, link)):
                try:
                    make()
                except OSError:
                    pass
                try:
                    if os.path.islink(link):
                        os.unlink(link)
                    elif os.path.isdir(link):
                        os.rename(link, real)
                except OSError:
                    pass

    flipper = threading.Thread(target=flip, daemon=True)
    flipper.start()
    outcomes = {"written": 0, "refused": 0}
    try:
        for k in range(300):
            try:
                with OutputFolder(root) as folder, folder.folder("optimized") as opt:
                    opt.write_text(f"f{k}.frag", "x\n")
                outcomes["written"] += 1
            except (RRCacheError, OSError):
                outcomes["refused"] += 1
    finally:
        stop.set()
        flipper.join()
    assert os.listdir(outside) == [], outcomes
    assert outcomes["written"] + outcomes["refused"] == 300


# ----------------------------------------------------------------------------- the commands

def test_report_out_to_a_private_device_fifo_or_folder(case, stability_case):
    folder, _ = case
    targets = {"fifo.html": "FIFO", "dir.html": "directory"}
    os.mkfifo(folder / "fifo.html")
    (folder / "dir.html").mkdir()
    if _device(folder / "null"):
        targets["null"] = "character device"
    if _device(folder / "full", 7):
        os.chmod(folder / "full", 0o666)
        targets["full"] = "character device"
    tc = stability_case("report --out a device, a FIFO, a folder", AREA,
                        "rrcache report P --out X, X a private mknod(1,3) or (1,7) node, a FIFO, a folder")
    seen, peaks = {}, []
    for name, kind in targets.items():
        before = os.lstat(folder / name)
        code, _, lines, peak, _ = rrcache_traced(folder, "report", "p", "--out", name, timeout=120)
        line = one_error_line(code, lines)
        after = os.lstat(folder / name)
        assert (after.st_mode, after.st_ino, after.st_rdev) == (before.st_mode, before.st_ino, before.st_rdev)
        assert kind in line and name in line, line
        seen[name] = line.replace(str(folder), "TMP")
        peaks.append(round(peak))
    tc.observe(**seen, peak_mib=max(peaks))
    assert max(peaks) < REFUSAL_PEAK_MIB, peaks


@pytest.mark.parametrize("name", ["optimized", "optimized/e1", "profile.lock", "profile.sqlite",
                                  "profile.sqlite-wal", "tradeoff.png", "report.html", "profile.json"])
def test_links_inside_a_profile_folder_send_no_write_outside(case, stability_case, name):
    folder, outside = case
    target = outside / ("dir" if name.startswith("optimized") else "file")
    if name.startswith("optimized"):
        target.mkdir()
        (target / "precious.frag").write_text("keep\n")
    else:
        target.write_text("keep\n")
    link = folder / "p" / name
    if link.is_dir() and not link.is_symlink():
        shutil.rmtree(link)
    elif link.exists() or link.is_symlink():
        link.unlink()
    os.symlink(target, link)
    before = tree(outside)
    contents = {p: open(p, "rb").read() for p in before}
    tc = stability_case(f"a link inside the profile folder: {name}", AREA,
                        f"p/{name} -> outside; rrcache profile --out p again, then rrcache report p")
    code, _, lines, peak, _ = rrcache_traced(folder, "profile", "scene.frag", "scene.json", "--out", "p",
                                             *QUICK_PROFILE)
    line = one_error_line(code, lines)
    report, _, report_lines, report_peak, _ = rrcache_traced(folder, "report", "p", timeout=120)
    assert tree(outside) == before and {p: open(p, "rb").read() for p in before} == contents
    assert os.path.islink(link)
    assert "symbolic link" in line and name.split("/")[-1] in line, line
    assert report in (0, 2), report_lines
    if report == 2:
        one_error_line(report, report_lines)
    tc.observe(exit=code, stderr=line.replace(str(folder), "TMP"), report_exit=report, peak_mib=round(peak),
               report_peak_mib=round(report_peak))
    assert max(peak, report_peak) < RUN_PEAK_MIB, (peak, report_peak)
