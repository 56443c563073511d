"""``fileio.json_depth``: the nesting check every reader of hostile JSON uses (the manifest
for resume and export, the metric tables) before walking a document."""

from __future__ import annotations

import pytest

from seahaze.fileio import json_depth


@pytest.mark.parametrize(
    ("document", "depth"),
    [(5, 1), ([], 1), ([[1]], 3), ({"a": {"b": []}}, 3), ({"a": 1, "b": [[2]]}, 4)],
)
def test_depth_counts_every_level_scalars_included(document, depth):
    assert json_depth(document, 64) == depth


def test_a_document_deeper_than_python_recursion_is_measured_without_recursing():
    deep: list = []
    for _ in range(49_999):  # built by a loop: a recursive walk would exhaust the stack
        deep = [deep]
    assert json_depth(deep, 64) == 65
    assert json_depth(deep, 100_000) == 50_000
