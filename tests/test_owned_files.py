"""seahaze never deletes or overwrites a file it did not write, whatever its record says.

The record of its files (``.seahaze-owned.json``) lies in a folder other people can write to, so
these tests plant records as an attacker or an accident would: paths that climb out of the
folder, absolute paths, paths through a symbolic link that leads outside, a user's file of the
same name as one seahaze wrote, a record seahaze did not write. Every file outside what seahaze
wrote is checked byte for byte afterwards.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from seahaze.cli import main
from seahaze.dataset.owned import RECORD_NAME, OwnedFiles, plain_relative


def _export(dataset: Path, out: Path, *extra: str) -> int:
    return main(["export", str(dataset), "--layout", "paired", "--out", str(out), *extra])


def _snapshot(paths: list[Path]) -> dict[Path, bytes]:
    return {p: p.read_bytes() for p in paths}


@pytest.mark.parametrize(
    ("rel", "plain"),
    [
        ("train/GT/a.png", "train/GT/a.png"),
        ("../victim.txt", None),
        ("/etc/passwd", None),
        ("train/../../x", None),
        ("train//a.png", None),
        ("./a.png", None),
        ("a\\b.png", None),
        ("", None),
        ("a\x00b", None),
        ("x" * 2000, None),
        (7, None),
    ],
)
def test_only_plain_paths_inside_the_folder_are_read(rel, plain) -> None:
    assert plain_relative(rel) == plain


def test_a_planted_record_deletes_nothing(split_dataset, tmp_path, capsys) -> None:
    # The attack of the hostile-input pass: a record listing files outside --out and a user's
    # file inside it, as if an earlier export had written them.
    victim = tmp_path / "victim.txt"
    victim.write_text("outside, relative")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    absolute = elsewhere / "victim2.txt"
    absolute.write_text("outside, absolute")
    through = elsewhere / "through.png"
    through.write_text("outside, through a link")
    out = tmp_path / "view"
    out.mkdir()
    keep = out / "keep_me.txt"
    keep.write_text("the user's")
    (out / "linked").symlink_to(elsewhere, target_is_directory=True)
    st = os.lstat(keep)
    identity = [st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns]
    record = {
        "format": "seahaze-owned/2",
        "tool": "seahaze export",
        "files": {
            "../victim.txt": identity,
            str(absolute): identity,
            "keep_me.txt": identity,  # its true identity: the record is what is not trusted
            "linked/through.png": identity,
        },
    }
    (out / RECORD_NAME).write_text(json.dumps(record))
    before = _snapshot([victim, absolute, through, keep])
    assert _export(split_dataset, out) == 0
    err = capsys.readouterr().err
    assert "not a record seahaze wrote" in err and "'../victim.txt' is not a path" in err
    assert _snapshot([victim, absolute, through, keep]) == before
    # A second export, on the record seahaze wrote itself, still leaves all of them alone.
    assert _export(split_dataset, out, "--levels", "2000") == 0
    assert _snapshot([victim, absolute, through, keep]) == before
    assert (out / "linked").is_symlink()


def test_the_legacy_record_format_is_trusted_with_nothing(split_dataset, tmp_path, capsys) -> None:
    out = tmp_path / "old"
    out.mkdir()
    keep = out / "keep_me.txt"
    keep.write_text("the user's")
    legacy = {"format": "seahaze-owned/1", "files": ["keep_me.txt", "../victim.txt"]}
    (out / RECORD_NAME).write_text(json.dumps(legacy))
    (tmp_path / "victim.txt").write_text("outside")
    assert _export(split_dataset, out) == 0
    assert keep.read_text() == "the user's" and (tmp_path / "victim.txt").read_text() == "outside"


def test_a_file_replaced_since_is_never_overwritten_or_deleted(split_dataset, tmp_path, capsys):
    out = tmp_path / "view"
    assert _export(split_dataset, out) == 0
    mine = sorted(out.rglob("*_v0500.png"))[0]
    mine.unlink()
    mine.write_bytes(b"my own picture under seahaze's name")
    # Overwriting it: refused, nothing written.
    assert _export(split_dataset, out) == 2
    err = capsys.readouterr().err
    assert str(mine) in err and "never overwritten" in err
    assert mine.read_bytes() == b"my own picture under seahaze's name"
    # Deleting it as a stale file of the earlier export: left alone, and said so; the other
    # 500 m files, still as seahaze wrote them, are removed.
    assert _export(split_dataset, out, "--levels", "2000") == 0
    err = capsys.readouterr().err
    assert f"{mine}: kept, not as seahaze wrote it" in err
    assert mine.read_bytes() == b"my own picture under seahaze's name"
    assert sorted(out.rglob("*_v0500.png")) == [mine]


def test_a_record_that_is_a_link_or_junk_is_refused(tmp_path) -> None:
    from seahaze.dataset.owned import ForeignFileError

    folder = tmp_path / "f"
    folder.mkdir()
    (tmp_path / "real.json").write_text(json.dumps({"format": "seahaze-owned/2", "files": {}}))
    (folder / RECORD_NAME).symlink_to(tmp_path / "real.json")
    with pytest.raises(ForeignFileError, match="not a regular file"):
        OwnedFiles.open(folder)
    (folder / RECORD_NAME).unlink()
    (folder / RECORD_NAME).write_text('{"format": "seahaze-owned/2", "files": 3}')
    with pytest.raises(ForeignFileError, match="cannot read"):
        OwnedFiles.open(folder)
