"""Atomic writes and output-folder confinement, on the real file system."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from seamless_usd.errors import InputError
from seamless_usd.fileio import atomic_write, atomic_write_bytes, atomic_write_text, confine


def _leftovers(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir() if ".tmp" in p.name)


# values ---------------------------------------------------------------------------------------


def test_atomic_write_text_and_bytes_create_and_replace(tmp_path: Path) -> None:
    target = tmp_path / "report.json"
    assert atomic_write_text(target, "{}\n") == target
    assert target.read_text() == "{}\n"
    atomic_write_bytes(target, b"\x00\x01")
    assert target.read_bytes() == b"\x00\x01"
    assert _leftovers(tmp_path) == []


def test_temp_name_keeps_extension_and_directory(tmp_path: Path) -> None:
    seen: list[Path] = []

    def writer(tmp: Path) -> None:
        seen.append(tmp)
        tmp.write_bytes(b"png")

    atomic_write(tmp_path / "albedo.png", writer)
    assert seen[0].parent == tmp_path
    assert seen[0].suffix == ".png"
    assert seen[0] != tmp_path / "albedo.png"


def test_writer_failing_midway_leaves_old_file_and_no_temp(tmp_path: Path) -> None:
    target = tmp_path / "map.png"
    target.write_bytes(b"old content")

    def writer(tmp: Path) -> None:
        with open(tmp, "wb") as f:
            f.write(b"half of the new")
            raise RuntimeError("disk full")

    with pytest.raises(RuntimeError, match="disk full"):
        atomic_write(target, writer)
    assert target.read_bytes() == b"old content"
    assert _leftovers(tmp_path) == []


def test_writer_failing_on_new_target_leaves_nothing(tmp_path: Path) -> None:
    def writer(tmp: Path) -> None:
        tmp.write_bytes(b"partial")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(tmp_path / "new.exr", writer)
    assert list(tmp_path.iterdir()) == []


def test_writer_that_writes_nothing_is_an_error(tmp_path: Path) -> None:
    def writer(tmp: Path) -> None:
        tmp.unlink()

    with pytest.raises(RuntimeError, match="did not create"):
        atomic_write(tmp_path / "x.txt", writer)
    assert list(tmp_path.iterdir()) == []


def test_replacing_keeps_the_old_permissions(tmp_path: Path) -> None:
    target = tmp_path / "a.txt"
    target.write_text("x")
    target.chmod(0o640)
    atomic_write_text(target, "y")
    assert target.stat().st_mode & 0o777 == 0o640


def test_new_file_gets_umask_permissions_not_0600(tmp_path: Path) -> None:
    target = atomic_write_text(tmp_path / "a.txt", "y")
    umask = os.umask(0)
    os.umask(umask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~umask


def _make_read_only(directory: Path):
    """Make ``directory`` unwritable even for root (immutable flag), or skip; returns an undo."""
    if os.geteuid() != 0:
        directory.chmod(0o555)
        return lambda: directory.chmod(0o755)
    chattr = shutil.which("chattr")
    if chattr is None or subprocess.run([chattr, "+i", str(directory)], capture_output=True).returncode:
        pytest.skip("running as root without a way to make a folder read-only")
    return lambda: subprocess.run([chattr, "-i", str(directory)], check=True)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX permissions")
def test_read_only_directory_is_an_input_error(tmp_path: Path) -> None:
    ro = tmp_path / "ro"
    ro.mkdir()
    (ro / "keep.txt").write_text("old")
    undo = _make_read_only(ro)
    try:
        with pytest.raises(InputError, match=r"@.*keep\.txt@.*permissions"):
            atomic_write_text(ro / "keep.txt", "new")
        assert (ro / "keep.txt").read_text() == "old"
        assert _leftovers(ro) == []
    finally:
        undo()


def test_read_only_target_in_writable_directory_is_replaced(tmp_path: Path) -> None:
    # os.replace swaps directory entries: a read-only file in a writable folder is replaced, as
    # every atomic writer does; the new file keeps the read-only mode.
    target = tmp_path / "ro.txt"
    target.write_text("old")
    target.chmod(0o444)
    atomic_write_text(target, "new")
    assert target.read_text() == "new"
    assert target.stat().st_mode & 0o777 == 0o444


def test_missing_directory_is_an_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="does not exist"):
        atomic_write_text(tmp_path / "nope" / "a.txt", "x")


# confine --------------------------------------------------------------------------------------


def test_confine_relative_and_absolute_inside(tmp_path: Path) -> None:
    root = tmp_path / "tileable"
    root.mkdir()
    assert confine("a/b.png", root) == (root / "a" / "b.png").resolve()
    assert confine(root / "c.png", root) == (root / "c.png").resolve()
    assert confine("x/../c.png", root) == (root / "c.png").resolve()


@pytest.mark.parametrize("bad", ["../../etc/passwd", "../sibling.png", "a/../../b.png", "/etc/passwd"])
def test_confine_refuses_escapes(tmp_path: Path, bad: str) -> None:
    root = tmp_path / "tileable"
    root.mkdir()
    with pytest.raises(InputError, match="outside the output folder"):
        confine(bad, root)


def test_confine_refuses_symlink_escape(tmp_path: Path) -> None:
    root = tmp_path / "tileable"
    root.mkdir()
    (root / "link").symlink_to(tmp_path)
    with pytest.raises(InputError):
        confine("link/evil.png", root)


def test_confine_refuses_prefix_sibling(tmp_path: Path) -> None:
    root = tmp_path / "out"
    root.mkdir()
    (tmp_path / "out2").mkdir()
    with pytest.raises(InputError):
        confine(tmp_path / "out2" / "a.png", root)
