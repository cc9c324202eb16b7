"""The package's layering (docs/ARCHITECTURE.md "Python packages"): every import inside
proleg goes to the same layer or a lower one, so there are no cycles between packages.
Read from the source with ast (lazy imports inside functions count too)."""

from __future__ import annotations

import ast
from pathlib import Path

import proleg

ROOT = Path(proleg.__file__).resolve().parent

#: lowest first; a module may import from its own layer or any layer before it
LAYERS: list[set[str]] = [
    {"__init__", "errors", "interrupts", "names", "paths", "states", "outputs", "ports", "typed"},
    {"transitions", "protocol"},
    {"body", "physics", "robot", "robot_fields", "robot_limbs", "robot_settings", "robot_transitions", "robot_transitions_csv", "robot_entries", "robot_plant", "robot_body",
     "robot_reach", "robot_pose", "robot_coupling", "robot_descents", "robot_climb", "gait", "convert", "limbloss"},
    {"firmware"},
    {"sim", "emu"},
    {"link"},
    {"record", "plot", "console", "report", "learn"},
    {"cli"},
    {"demo", "__main__"},
]
RANK = {name: i for i, layer in enumerate(LAYERS) for name in layer}


def _top(path: Path) -> str:
    rel = path.relative_to(ROOT)
    return rel.parts[0].removesuffix(".py")


def _imports(path: Path) -> set[str]:
    rel = path.relative_to(ROOT)
    package = list(rel.parts[:-1])
    out = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)]
                mod = base + (node.module.split(".") if node.module else [])
                out.add(mod[0] if mod else (node.names[0].name if not node.module else node.module))
                if not mod:
                    out.add("__init__")
            elif node.module and node.module.split(".")[0] == "proleg":
                parts = node.module.split(".")
                out.add(parts[1] if len(parts) > 1 else "__init__")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] == "proleg":
                    out.add(parts[1] if len(parts) > 1 else "__init__")
    return out


def test_every_package_is_in_a_layer():
    tops = {_top(p) for p in ROOT.rglob("*.py")}
    assert tops - set(RANK) == set(), "add new packages to LAYERS (and docs/ARCHITECTURE.md)"


def test_no_import_goes_to_a_higher_layer():
    bad = []
    for path in sorted(ROOT.rglob("*.py")):
        src = _top(path)
        for dst in _imports(path):
            if dst in RANK and src in RANK and RANK[dst] > RANK[src]:
                bad.append(f"{path.relative_to(ROOT)} imports {dst} (layer {RANK[dst]} > {RANK[src]})")
    assert bad == []


def test_link_and_sim_no_longer_import_each_other_upward():
    sim_imports = set().union(*(_imports(p) for p in (ROOT / "sim").rglob("*.py")))
    assert "link" not in sim_imports and "report" not in sim_imports
