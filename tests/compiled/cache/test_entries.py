"""Cache entries on disk (compiled/cache/entries.py, docs/architecture.md#rule-18).

References: the bytes that were written and sha256sum. An entry reads back exactly as it
was written, its checksum is sha256sum's line for it, and nothing else is ever handed
back: a damaged entry is refused with a CacheWarning that names the file, removed, and
built again once. A reader that meets a writer between its two moves (the file in place,
its checksum not yet) waits for the writer instead of calling the entry damaged.
"""

from __future__ import annotations

import hashlib
import shutil
import subprocess
import threading
import time
import warnings

import pytest
from support.damage import DAMAGES

from lightcraft_opt.compiled.cache import (
    CacheWarning,
    EntryStatus,
    cache_dir,
    check_entry,
    checksum_path,
    entry_file,
    load_entry,
    read_entry,
    write_entry,
)
from lightcraft_opt.compiled.cache import entries as entries_module

DATA = bytes(range(256)) * 40


@pytest.fixture
def entry(tmp_path, monkeypatch):
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(tmp_path / "cache"))
    return cache_dir() / "table-k1.bin"


def test_an_entry_reads_back_as_written_with_a_sha256sum_checksum(entry):
    assert read_entry(entry) is None  # never written: a miss, no warning
    write_entry(entry, DATA)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        assert read_entry(entry) == DATA
    line = checksum_path(entry).read_text()
    assert line == f"{hashlib.sha256(DATA).hexdigest()}  {entry.name}\n"
    if shutil.which("sha256sum"):
        check = subprocess.run(
            ["sha256sum", "-c", checksum_path(entry).name], cwd=entry.parent, capture_output=True
        )
        assert check.returncode == 0, check.stdout
    assert not [p for p in entry.parent.iterdir() if p.name.startswith(".")]  # no temporary


@pytest.mark.parametrize("damage", DAMAGES)
def test_a_damaged_entry_is_refused_named_and_removed(entry, damage):
    write_entry(entry, DATA)
    spoil, fault = DAMAGES[damage]
    spoil(entry)
    assert check_entry(entry).status is EntryStatus.DAMAGED
    assert fault in check_entry(entry).fault
    with pytest.warns(CacheWarning, match="damaged") as record:
        assert read_entry(entry) is None
    message = str(record[0].message)
    assert len(record) == 1 and str(entry) in message and fault in message
    assert check_entry(entry).status is EntryStatus.ABSENT
    assert not checksum_path(entry).exists()


def test_an_entry_that_does_not_decode_is_refused_and_removed(entry):
    """A whole file whose contents its reader rejects (another layout, a library it calls
    gone) is unusable all the same."""
    write_entry(entry, b"not a table")

    def decode(data: bytes) -> int:
        raise ValueError("no table in it")

    with pytest.warns(CacheWarning, match="cannot be loaded \\(no table in it\\)"):
        assert load_entry(entry, decode, (ValueError,)) is None
    assert check_entry(entry).status is EntryStatus.ABSENT
    write_entry(entry, b"12")
    assert load_entry(entry, int, (ValueError,)) == 12


def test_a_reader_waits_for_a_writer_between_its_two_moves(entry):
    """The writer holds the entry's lock, has moved the new file into place and not yet
    its checksum: the reader finds them apart, waits for the lock, reads again and gets
    the new entry, with no warning."""
    write_entry(entry, b"old")
    moved, done = threading.Event(), threading.Event()

    def writer() -> None:
        with entries_module._locked(entry):
            entries_module._replace(entry, DATA)
            moved.set()
            time.sleep(0.3)
            line = entries_module._checksum_line(entry, hashlib.sha256(DATA).hexdigest())
            entries_module._replace(checksum_path(entry), line)
            done.set()  # inside the lock: the reader cannot get in before this

    thread = threading.Thread(target=writer)
    thread.start()
    moved.wait()
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        assert read_entry(entry) == DATA
    assert done.is_set()
    thread.join()


def test_a_file_entry_is_built_once_and_a_damaged_one_again(entry):
    """entry_file: built on a miss, returned untouched on a hit, built again (with the
    warning) when damaged; two threads that miss together build it once."""
    builds: list[int] = []

    def build(target) -> None:
        time.sleep(0.1)
        builds.append(1)
        target.write_bytes(DATA)

    threads = [threading.Thread(target=entry_file, args=(entry, build)) for _ in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len(builds) == 1 and entry.read_bytes() == DATA
    assert entry_file(entry, build) == entry and len(builds) == 1
    DAMAGES["half"][0](entry)
    with pytest.warns(CacheWarning, match="is damaged"):
        assert entry_file(entry, build) == entry
    assert len(builds) == 2 and check_entry(entry).status is EntryStatus.WHOLE


def test_a_failed_build_leaves_no_entry(entry):
    def build(target) -> None:
        target.write_bytes(DATA[:10])
        raise RuntimeError("the compiler stopped")

    with pytest.raises(RuntimeError, match="the compiler stopped"):
        entry_file(entry, build)
    assert check_entry(entry).status is EntryStatus.ABSENT
    assert [p.name for p in entry.parent.iterdir()] == [entry.name + ".lock"]


def test_an_unwritable_cache_warns_and_the_run_goes_on(tmp_path, monkeypatch):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(blocker / "cache"))
    entry = cache_dir() / "table-k1.bin"
    with pytest.warns(CacheWarning, match="could not write the cache file"):
        write_entry(entry, DATA)
    with pytest.warns(CacheWarning, match="is unreadable"):
        assert read_entry(entry) is None
