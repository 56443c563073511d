"""Generate docs/scenes.md, the scene YAML reference, from the schema in seahaze.spec.

Run ``make docs`` (or this script) after changing the schema; a test checks the committed file
is up to date, so the reference cannot drift from the code.
"""

from __future__ import annotations

import inspect
import sys
from enum import Enum
from pathlib import Path
from typing import Any

from pydantic import BaseModel
from pydantic_core import PydanticUndefined

from seahaze.spec import SceneSpec, field_bounds, model_in

OUT = Path(__file__).resolve().parents[1] / "docs" / "scenes.md"

INTRO = """# Scene YAML reference

A scene file describes one scene: camera, sun, sky, sea, vessels, haze and render settings.
Every section and key is optional; unknown keys are errors (`seahaze validate SCENE.yaml` lists
every problem with its line). World frame: Z up, metres, sea level at z = 0, the camera above
the origin; azimuths and headings are degrees counter-clockwise from +x seen from above.

This page is generated from `src/seahaze/spec.py` by `scripts/gen_scene_docs.py`; do not edit it
by hand.

Example (`scenes/default.yaml`):

```yaml
{example}
```

Vessels, explicit and sampled (they can be combined; sampled ones never overlap the explicit
ones). `seahaze classes` lists the classes with their YOLO ids and length ranges:

```yaml
vessels:
  placed:                       # bearing: from the camera heading, positive to the left
    - {{class: tug, distance_m: 420, bearing_deg: 12, heading_deg: 200, length_m: 30}}
    - {{class: tanker, distance_m: 2600, bearing_deg: -20, heading_deg: 10}}  # length sampled
  sample:
    count: 6
    classes: {{container_ship: 2, fishing_boat: 3, buoy: 1}}   # relative weights
    distance_m: [150, 4000]
    distribution: log           # as many vessels per octave of distance
    bearing_spread_deg: 25      # half-width; default: inside the field of view
    min_separation_m: 40
    seed: 3
```

A vessel from your own mesh file, and hulls that pitch and roll with the waves. The mesh keeps
its own materials; the placed vessel's `class` gives its boxes their YOLO id. A missing,
unreadable or unsupported file is reported with its line like any other mistake. The
conventions (axes, scale, draft) are in `assets/README.md`:

```yaml
vessels:
  follow_slope: true                # pitch and roll to the local sea slope (default: upright)
  placed:
    - class: fishing_boat           # what the mesh is labelled as
      distance_m: 250
      bearing_deg: 5
      heading_deg: 120
      mesh:
        path: meshes/workboat.ply   # absolute, relative to this YAML file, or to assets/
        scale_m: 16                 # overall length after scaling (m), not a factor
        up_axis: "+y"               # the file's up and bow axes (glTF exports: +y up)
        forward_axis: "+z"
        draft_m: 0.9                # default: 10 % of the scaled height
```
"""


def _type_name(annotation: Any) -> str:
    text = getattr(annotation, "__name__", None) if isinstance(annotation, type) else None
    text = text or str(annotation)
    for old, new in (
        ("typing.", ""),
        ("Annotated[", ""),
        ("seahaze.spec.", ""),
        ("seahaze.visibility.", ""),
        ("NoneType", "null"),
    ):
        text = text.replace(old, new)
    if "Literal" in text:
        return (
            "one of "
            + ", ".join(f"`{a}`" for a in getattr(annotation, "__args__", ()) if isinstance(a, str))
            or text
        )
    if isinstance(annotation, type) and issubclass(annotation, Enum):
        return "one of " + ", ".join(f"`{member.value}`" for member in annotation)
    if "tuple[" in text and "float" in text:
        return "list of numbers"
    if "tuple[" in text and "int" in text:
        return "list of integers"
    text = text.split(",")[0].replace("[", "") if "Field" in text else text
    # A bare "|" would split the Markdown table cell.
    return text.replace(" | None", " or null").replace(" | ", " or ")


def _range(info) -> str:
    symbols = {"ge": "≥", "gt": ">", "le": "≤", "lt": "<"}
    return ", ".join(f"{symbols[kind]} {value:g}" for kind, value in field_bounds(info))


def _default(info) -> str:
    if info.default is not PydanticUndefined:
        value = info.default
        if isinstance(value, tuple):
            value = list(value)
        return f"`{value}`" if value is not None else "—"
    if info.default_factory is not None:
        value = info.default_factory()
        if isinstance(value, BaseModel):
            return "(section)"
        return f"`{value}`" if value not in ([], {}) else "`[]`"
    return "required"


def section(model: type[BaseModel], path: str) -> list[str]:
    """Markdown for one section and, recursively, its sub-sections."""
    lines = [
        f"## `{path}`" if path else "## Top level",
        "",
        inspect.cleandoc(model.__doc__ or ""),
        "",
        "| key | type | unit | default | allowed | meaning |",
        "|---|---|---|---|---|---|",
    ]
    nested = []
    for name, info in model.model_fields.items():
        key = info.alias or name
        sub = model_in(info.annotation)
        extra = info.json_schema_extra if isinstance(info.json_schema_extra, dict) else {}
        unit = extra.get("unit", "")
        kind = f"section `{sub.__name__}`" if sub else _type_name(info.annotation)
        desc = (
            info.description or (sub.__doc__ or "").strip().splitlines()[0]
            if sub
            else info.description or ""
        )
        lines.append(f"| `{key}` | {kind} | {unit} | {_default(info)} | {_range(info)} | {desc} |")
        if sub:
            nested.append((sub, f"{path}.{key}" if path else key, "list" in str(info.annotation)))
    lines.append("")
    for sub, sub_path, is_list in nested:
        lines += section(sub, f"{sub_path}[]" if is_list else sub_path)
    return lines


def render() -> str:
    """The full text of docs/scenes.md."""
    example = (OUT.parents[1] / "scenes" / "default.yaml").read_text().strip()
    return INTRO.format(example=example) + "\n" + "\n".join(section(SceneSpec, "")) + "\n"


def main() -> int:
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(render())
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
