"""The geometry package's layout rules (issue 20): no module imports another's private names;
imports inside functions only for the heavy optional libraries; no module over ~500 lines without
the reason at the top of its docstring; one module per job for the preprocessing chain."""

from __future__ import annotations

import ast
from pathlib import Path

import steamtwin.geometry

ROOT = Path(steamtwin.geometry.__file__).parent
#: Libraries a geometry function may import where it uses them: each costs a second or more to
#: import, and only some steps need it.
DEFERRED = ("open3d", "gmsh", "trimesh", "meshio", "matplotlib.pyplot")
MAX_LINES = 500


def _modules() -> dict[str, ast.Module]:
    return {path.name: ast.parse(path.read_text(encoding="utf-8")) for path in ROOT.glob("*.py")}


def test_no_private_name_is_imported_from_another_module():
    found = [f"{name}: from {node.module} import {alias.name}"
             for name, tree in _modules().items() for node in ast.walk(tree)
             if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("steamtwin")
             for alias in node.names if alias.name.startswith("_")]
    assert found == []


def test_function_level_imports_are_heavy_optional_libraries_only():
    found = []
    for name, tree in _modules().items():
        top = {id(node) for node in tree.body}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import | ast.ImportFrom) and id(node) not in top:
                module = node.module if isinstance(node, ast.ImportFrom) else node.names[0].name
                if not module.startswith(DEFERRED):
                    found.append(f"{name}:{node.lineno}: {module}")
    assert found == []


def test_long_modules_state_their_reason():
    long = [path.name for path in ROOT.glob("*.py")
            if len(path.read_text(encoding="utf-8").splitlines()) > MAX_LINES
            and "Kept as one module because" not in (ast.get_docstring(
                ast.parse(path.read_text(encoding="utf-8"))) or "")]
    assert long == []


def test_rigid_fits_are_written_once():
    """Kabsch's SVD and Rodrigues' formula live in rigid.py alone."""
    for path in ROOT.glob("*.py"):
        if path.name == "rigid.py":
            continue
        text = path.read_text(encoding="utf-8")
        assert "np.linalg.det(vt.T @ u.T)" not in text, path.name
        assert "(1.0 - math.cos(angle)) * k @ k" not in text, path.name
