"""The dataset card README.md (issue 18): written when a batch finishes, from dataset.json and
the labels alone, so the same dataset gives the same bytes; a README.md seahaze did not write
is never replaced."""

from __future__ import annotations

import json
import re
import shutil
from collections import Counter
from pathlib import Path

from conftest import SPLIT_SCENES
from seahaze.cli import main
from seahaze.dataset import config_hash
from seahaze.dataset.card import CARD_MARKER, remove_card, write_card
from seahaze.vessels import CLASS_NAMES


def _card(root: Path) -> str:
    return (root / "README.md").read_text(encoding="utf-8")


def _counts_from_labels(root: Path) -> dict[str, Counter]:
    manifest = json.loads((root / "dataset.json").read_text())
    counts: dict[str, Counter] = {}
    for name, entry in manifest["scenes"].items():
        lines = (root / "labels" / "clean" / f"{name}.txt").read_text().splitlines()
        counts.setdefault(entry["split"], Counter()).update(int(line.split()[0]) for line in lines)
    return counts


def _table_row(card: str, label: str) -> list[int]:
    row = next(line for line in card.splitlines() if line.startswith(f"| {label} |"))
    return [int(cell) for cell in row.strip("|").split("|")[1:]]


def test_the_card_says_what_how_levels_counts_and_citation(split_dataset):
    card = _card(split_dataset)
    manifest = json.loads((split_dataset / "dataset.json").read_text())
    assert card.startswith(CARD_MARKER + "\n")
    assert f"config hash `{config_hash(manifest)}`" in card
    assert f"seahaze {manifest['seahaze_version']}" in card
    assert (
        "seahaze render tiny.yaml --scenes 6 --seed 3 --vis 500,2000 --res 64x36 --spp 1 "
        "--mode physical --split 0.5,0.25,0.25" in card
    )
    assert "| `v0500` | 500 | 0.007824 |" in card and "| `v2000` | 2000 | 0.001956 |" in card
    # Counts per split (train, val, test, total) match the label files.
    counts = _counts_from_labels(split_dataset)
    order = ["train", "val", "test"]
    scenes = Counter(e["split"] for e in manifest["scenes"].values())
    assert _table_row(card, "scenes") == [scenes[s] for s in order] + [SPLIT_SCENES]
    assert _table_row(card, "images (clean + levels)") == [3 * scenes[s] for s in order] + [18]
    vessels = [sum(counts.get(s, Counter()).values()) for s in order]
    assert _table_row(card, "vessels (all classes)") == [*vessels, sum(vessels)]
    assert sum(vessels) > 0
    for class_id in {c for counter in counts.values() for c in counter}:
        row = _table_row(card, f"`{CLASS_NAMES[class_id]}` (id {class_id})")
        assert row[:3] == [counts.get(s, Counter())[class_id] for s in order]
    assert "yolo val model=WEIGHTS.pt data=data.yaml split=" in card
    assert 'COCO("coco/v' in card and "seahaze export . --layout paired" in card
    assert "Feng, Wentao and Peng, Guobei and Mao, Wengang and Liu, Ryan Wen" in card
    assert "A New Visibility Estimation Metric for Maritime Surveillance" in card


def test_the_card_has_deterministic_bytes(split_dataset, tmp_path):
    card = _card(split_dataset)
    assert str(split_dataset.resolve()) not in card  # no absolute path
    assert not re.search(r"\b20\d\d-\d\d-\d\d\b|\d\d:\d\d:\d\d", card)  # no date or time
    moved = tmp_path / "moved"
    shutil.copytree(split_dataset, moved)
    (moved / "README.md").unlink()
    assert write_card(moved)
    assert _card(moved) == card


def test_a_readme_seahaze_did_not_write_is_kept(split_template, split_dataset, tmp_path, capsys):
    out = tmp_path / "theirs"
    shutil.copytree(split_dataset, out)
    (out / "README.md").write_text("# my notes\n")
    args = ["render", str(split_template), "--scenes", str(SPLIT_SCENES), "--split"]
    assert main([*args, "0.5,0.25,0.25", "--out", str(out), "--quiet"]) == 0
    assert "README.md was not written by seahaze: kept" in capsys.readouterr().err
    assert _card(out) == "# my notes\n"
    assert not write_card(out)


def test_a_folder_or_a_broken_link_named_readme_is_left_alone(split_dataset, tmp_path):
    for kind in ("folder", "link"):
        out = tmp_path / kind
        shutil.copytree(split_dataset, out)
        card = out / "README.md"
        card.unlink()
        if kind == "folder":
            card.mkdir()
        else:
            card.symlink_to(tmp_path / "missing.md")
        assert not write_card(out)  # not a card seahaze wrote: not replaced, no crash
        remove_card(out)  # nor deleted while scenes are pending
        assert card.is_dir() if kind == "folder" else card.is_symlink()
        assert not (tmp_path / "missing.md").exists()


def test_a_dataset_without_split_has_a_card_with_one_split(dataset):
    card = _card(dataset)
    assert "| | `all` | total |" in card
    assert "splits: none (made with `--split none`" in card
    assert "--split none" in card  # the command that makes it again, in a new folder too
