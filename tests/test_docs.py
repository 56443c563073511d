"""Generated documentation matches the code it is generated from."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_scene_reference_is_up_to_date():
    spec = importlib.util.spec_from_file_location(
        "gen_scene_docs", ROOT / "scripts" / "gen_scene_docs.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    committed = (ROOT / "docs" / "scenes.md").read_text()
    assert committed == module.render(), "docs/scenes.md is stale: run `make docs`"
