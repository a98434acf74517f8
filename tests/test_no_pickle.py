"""Nothing in the package unpickles a file: a grep over every module of src/steamtwin.

Unpickling runs whatever code the file names, so a planted checkpoint, ROM or table would run
code on the user's machine. The package stores data as JSON or ``.npz`` read with
``allow_pickle=False``. Pickling objects *to* worker processes (multiprocessing, Dask) loads
nothing from a file and is not matched.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "steamtwin"

UNPICKLING = re.compile(
    r"pickle\.loads?\b"                 # pickle.load / pickle.loads (also cloudpickle., dill.)
    r"|\bUnpickler\b"
    r"|allow_pickle\s*=\s*True"         # numpy's np.load(..., allow_pickle=True)
    r"|\bread_pickle\b"                 # pandas
    r"|\bjoblib\.load\b|\bdill\.loads?\b|\bshelve\.open\b|\bmarshal\.loads?\b"
    r"|from\s+(?:cloud)?pickle\s+import\s+[^\n]*\b(?:load|loads|Unpickler)\b"
)


def unpickling_lines(root: Path) -> list[str]:
    """``file:line: text`` of every line under ``root`` that unpickles (see UNPICKLING)."""
    found = []
    for path in sorted(root.rglob("*.py")):
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
            if UNPICKLING.search(line):
                found.append(f"{path.relative_to(root.parent)}:{number}: {line.strip()}")
    return found


def test_no_module_of_the_package_unpickles():
    assert PACKAGE.is_dir() and any(PACKAGE.rglob("*.py"))
    found = unpickling_lines(PACKAGE)
    assert not found, "unpickling in the package:\n" + "\n".join(found)


@pytest.mark.parametrize("line", [
    "state = pickle.load(handle)",
    "state = pickle.loads(data)",
    "class _Reader(pickle.Unpickler):",
    "archive = np.load(path, allow_pickle=True)",
    "archive = np.load(path, allow_pickle = True)",
    "frame = pd.read_pickle(path)",
    "model = joblib.load(path)",
    "from pickle import load",
    "from pickle import dumps, loads",
])
def test_the_grep_finds_unpickling(tmp_path, line):
    module = tmp_path / "steamtwin" / "planted.py"
    module.parent.mkdir()
    module.write_text(f"import pickle\n\n{line}\n", encoding="utf-8")
    assert unpickling_lines(module.parent) == [f"steamtwin/planted.py:3: {line}"]


@pytest.mark.parametrize("line", [
    "with np.load(path, allow_pickle=False) as archive:",
    "pool = ProcessPoolExecutor(workers, initializer=_start, initargs=(objective,))",
    "payload = pickle.dumps(objective)  # sent to workers, never read back from a file",
    "document = json.loads(text)",
])
def test_the_grep_passes_what_loads_no_pickle(tmp_path, line):
    module = tmp_path / "steamtwin" / "fine.py"
    module.parent.mkdir()
    module.write_text(f"{line}\n", encoding="utf-8")
    assert unpickling_lines(module.parent) == []
