import pytest

from mtmc.io import atomic_path, write_bytes_atomic, write_text_atomic


def test_text_and_bytes_round_trip(tmp_path):
    assert write_text_atomic(tmp_path / "a.txt", "x = 1\n").read_text() == "x = 1\n"
    assert write_bytes_atomic(tmp_path / "b.bin", b"\x00\x01").read_bytes() == b"\x00\x01"


def test_failure_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    dest = tmp_path / "result.json"
    dest.write_text("old")

    def failing_writer():
        with atomic_path(dest) as tmp:
            tmp.write_text("half a fi")
            raise RuntimeError("writer failed")

    with pytest.raises(RuntimeError):
        failing_writer()
    assert dest.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["result.json"]


def test_temporary_keeps_the_suffix_for_format_sniffing_writers(tmp_path):
    with atomic_path(tmp_path / "fig.svg") as tmp:
        assert tmp.suffix == ".svg"
        assert tmp.parent == tmp_path
        tmp.write_text("<svg/>")
    assert (tmp_path / "fig.svg").read_text() == "<svg/>"


def test_missing_folder_is_a_clear_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        write_text_atomic(tmp_path / "nope" / "a.txt", "x")


def test_file_mode_is_that_of_a_plain_open(tmp_path):
    import os

    plain = tmp_path / "plain.txt"
    plain.write_text("x")
    atomic = write_text_atomic(tmp_path / "atomic.txt", "x")
    assert os.stat(atomic).st_mode == os.stat(plain).st_mode


def test_symlink_is_followed_and_kept(tmp_path):
    import os

    target = tmp_path / "t.csv"
    target.write_text("old")
    link = tmp_path / "l.csv"
    os.symlink("t.csv", link)
    write_text_atomic(link, "new")
    assert link.is_symlink()
    assert os.readlink(link) == "t.csv"
    assert target.read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["l.csv", "t.csv"]


def test_dangling_symlink_creates_its_target(tmp_path):
    import os

    link = tmp_path / "l.csv"
    os.symlink("t.csv", link)
    write_text_atomic(link, "x")
    assert link.is_symlink()
    assert (tmp_path / "t.csv").read_text() == "x"


def test_existing_file_keeps_its_mode(tmp_path):
    import os
    import stat

    dest = tmp_path / "secret.json"
    dest.write_text("old")
    os.chmod(dest, 0o600)
    write_text_atomic(dest, "new")
    assert stat.S_IMODE(os.stat(dest).st_mode) == 0o600
    assert dest.read_text() == "new"


def test_fifo_is_written_through_not_replaced(tmp_path):
    import os
    import stat
    import threading

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    write_text_atomic(fifo, "a,b\n1,2\n")
    reader.join(timeout=10)
    assert got == [b"a,b\n1,2\n"]
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe"]


def _char_device(path, minor):
    """A copy of /dev/null (minor 3) or /dev/full (minor 7) at ``path``, or skip.

    The real /dev nodes are never used: a writer that replaced its destination would
    replace them for the whole machine when the tests run as root.
    """
    import os
    import stat

    try:
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, minor))
        with open(path, "wb"):
            pass
    except OSError:
        pytest.skip("cannot make a character device here (not root, or a nodev folder)")
    return path


def test_character_device_is_written_through(tmp_path):
    import os
    import stat

    dev = _char_device(tmp_path / "null", 3)
    before = os.stat(dev)
    write_text_atomic(dev, "discarded")
    after = os.stat(dev)
    assert stat.S_ISCHR(after.st_mode)
    assert after.st_ino == before.st_ino
    assert sorted(p.name for p in tmp_path.iterdir()) == ["null"]


def test_full_device_gives_an_os_error_and_stays_a_device(tmp_path):
    import os
    import stat

    dev = _char_device(tmp_path / "full", 7)
    with pytest.raises(OSError, match=f"^{dev}: cannot write: "):  # ENOSPC or EFBIG
        write_text_atomic(dev, "x" * 10_000)
    assert stat.S_ISCHR(os.stat(dev).st_mode)


def test_an_os_error_without_a_file_is_given_the_destination(tmp_path):
    from mtmc.io import atomic_path

    dest = tmp_path / "table.npy"
    with pytest.raises(OSError, match="No space") as info, atomic_path(dest):
        raise OSError(28, "No space left on device")
    assert str(info.value) == f"{dest}: cannot write: No space left on device"
    assert info.value.errno == 28
    with pytest.raises(OSError, match="requested") as info, atomic_path(dest):
        raise OSError("1000000 requested and 259568 written")
    assert str(info.value) == f"{dest}: cannot write: 1000000 requested and 259568 written"
    with pytest.raises(FileNotFoundError) as missing, atomic_path(dest):
        open(tmp_path / "nowhere" / "x")  # names its own file: unchanged
    assert missing.value.filename == str(tmp_path / "nowhere" / "x")
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_folder_destination_is_refused_with_a_message(tmp_path):
    (tmp_path / "d").mkdir()
    with pytest.raises(IsADirectoryError, match="is a folder"):
        write_text_atomic(tmp_path / "d", "x")
    assert (tmp_path / "d").is_dir()


def test_a_block_that_fails_after_ctrl_c_reports_the_interrupt() -> None:
    """Ctrl-C in a terminal reaches every process of the group: what the block waited on
    (a Dask worker) fails by it, and the interrupt, not that failure, is raised."""
    import os
    import signal

    from mtmc.io import deferred_interrupt

    def start(signalled: bool) -> None:
        with deferred_interrupt():
            if signalled:
                os.kill(os.getpid(), signal.SIGINT)
            raise RuntimeError("Nanny failed to start.")

    with pytest.raises(KeyboardInterrupt):
        start(True)
    with pytest.raises(RuntimeError, match="Nanny"):  # no signal: the failure is the error
        start(False)
