"""The package's arrows point one way (README, "Layout"): no module imports from a layer above its own."""
import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "depthtrack"

#: Layer of each top-level module or package; an import may only go to the same or a lower layer.
LAYER = {"contract": 0, "errors": 0, "progress": 0, "rotations": 0, "data": 0, "shaders": 0,
         "environment": 0,
         "camera": 1, "likelihood": 1, "io": 2, "body": 3,
         "render": 4, "detect": 4, "motion": 4, "filters": 4,
         "synth": 5, "track": 5, "swim": 5, "evaluate": 6, "export": 6, "cli": 7,
         "__init__": 8, "__main__": 8}


def upward_imports():
    found = []
    for path in PACKAGE.rglob("*.py"):
        rel = path.relative_to(PACKAGE.parent).with_suffix("").parts    # ('depthtrack', 'io', 'bvh', 'parse')
        source = rel[1]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.level:
                base = list(rel[:len(rel) - node.level])
                target = base + (node.module.split(".") if node.module else [])
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("depthtrack."):
                target = node.module.split(".")
            else:
                continue
            if len(target) < 2:
                continue
            if LAYER[target[1]] > LAYER[source]:
                found.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: {source} -> {target[1]}")
    return found


def test_every_top_level_module_has_a_layer():
    names = {p.stem if p.is_file() else p.name for p in PACKAGE.iterdir()
             if (p.suffix == ".py" or p.is_dir()) and not p.name.startswith("__pycache__")}
    assert names <= set(LAYER), f"add to LAYER: {sorted(names - set(LAYER))}"


def test_no_import_runs_up_the_layers():
    assert upward_imports() == []


def test_the_check_sees_an_upward_import(tmp_path, monkeypatch):
    # the check itself must be able to fail: a module of io importing from track is caught
    fake = tmp_path / "depthtrack"
    (fake / "io").mkdir(parents=True)
    (fake / "io" / "bad.py").write_text("from ..track import run\n")
    monkeypatch.setattr(__import__(__name__), "PACKAGE", fake)
    assert upward_imports() == ["depthtrack/io/bad.py:1: io -> track"]
