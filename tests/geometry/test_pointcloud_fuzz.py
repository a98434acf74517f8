"""Fuzzing the point-cloud readers (issue 16): any bytes and any damage to a valid PLY or PCD
file either read back as the header's count of finite points or raise PointCloudError; never
another exception, never points the file does not hold (zeros in place of missing rows)."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import open3d as o3d
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from steamtwin.geometry.pointcloud import PointCloudError, read_point_cloud, write_point_cloud

CLOUD = np.random.default_rng(7).normal(scale=0.02, size=(120, 3))
FUZZ = settings(max_examples=150, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture])
COUNTER = itertools.count()


def _ascii_ply(path: Path) -> None:
    header = ("ply\nformat ascii 1.0\ncomment fuzz base\nelement vertex 120\n"
              "property double x\nproperty double y\nproperty double z\nend_header\n")
    path.write_text(header + "".join(" ".join(f"{v:.17g}" for v in row) + "\n"
                                     for row in CLOUD))


def _ascii_pcd(path: Path) -> None:
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(CLOUD))
    o3d.io.write_point_cloud(str(path), cloud, write_ascii=True)


WRITERS = {"binary.ply": lambda path: write_point_cloud(CLOUD, path),
           "ascii.ply": _ascii_ply,
           "binary.pcd": lambda path: write_point_cloud(CLOUD, path),
           "ascii.pcd": _ascii_pcd}
#: How each base file declares its point count.
COUNT_TEXT = {"ply": [b"element vertex 120"], "pcd": [b"WIDTH 120", b"POINTS 120"]}


@pytest.fixture(scope="module")
def base_files(tmp_path_factory) -> dict[str, tuple[bytes, np.ndarray]]:
    """Each valid base file's bytes and the points it reads back as."""
    folder = tmp_path_factory.mktemp("base")
    files = {}
    for name, write in WRITERS.items():
        path = folder / name
        write(path)
        files[name] = (path.read_bytes(), read_point_cloud(path))
    return files


def _read(folder: Path, name: str, data: bytes) -> np.ndarray | None:
    """The points of ``data`` written as a file named like ``name``, or None if the reader
    refused it with a PointCloudError (any other exception fails the test)."""
    path = folder / f"{next(COUNTER)}_{name}"
    path.write_bytes(data)
    try:
        return read_point_cloud(path)
    except PointCloudError as error:
        assert path.name in str(error)
        return None
    finally:
        path.unlink()


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


PREFIXES = [b"", b"ply\n", b"ply\nformat ascii 1.0\nelement vertex 120\n",
            b"ply\nformat binary_little_endian 1.0\nelement vertex 120\nproperty float x\n"
            b"property float y\nproperty float z\nend_header\n",
            b"# .PCD v0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 120\nDATA binary\n"]


@FUZZ
@given(prefix=st.sampled_from(PREFIXES), noise=st.binary(max_size=2000),
       suffix=st.sampled_from([".ply", ".pcd", ".xyz"]))
def test_arbitrary_bytes_are_refused_or_read_as_declared(folder, prefix: bytes, noise: bytes,
                                                         suffix: str) -> None:
    points = _read(folder, f"noise{suffix}", prefix + noise)
    if points is not None:  # only a well-formed header with a body of finite values gets here
        assert prefix and points.shape == (120, 3) and np.all(np.isfinite(points))


@FUZZ
@given(name=st.sampled_from(sorted(WRITERS)), fraction=st.floats(0.0, 1.0, exclude_max=True))
def test_truncated_files_are_refused(folder, base_files, name: str, fraction: float) -> None:
    data, _ = base_files[name]
    assert _read(folder, name, data[:int(fraction * len(data))]) is None


@FUZZ
@given(name=st.sampled_from(sorted(WRITERS)), count=st.integers(0, 10**7))
def test_a_changed_count_in_the_header_is_refused(folder, base_files, name: str,
                                                  count: int) -> None:
    data, expected = base_files[name]
    if count == len(expected):
        return
    for text in COUNT_TEXT[name[-3:]]:
        assert text in data
        data = data.replace(text, text.replace(b"120", str(count).encode()))
    assert _read(folder, name, data) is None


@FUZZ
@given(name=st.sampled_from(sorted(WRITERS)),
       flips=st.lists(st.tuples(st.floats(0.0, 1.0, exclude_max=True), st.integers(0, 255)),
                      min_size=1, max_size=3))
def test_flipped_bytes_change_at_most_the_rows_they_hit(folder, base_files, name: str,
                                                        flips: list[tuple[float, int]]) -> None:
    data, expected = base_files[name]
    mutated = bytearray(data)
    for where, byte in flips:
        mutated[int(where * len(data))] = byte
    points = _read(folder, name, bytes(mutated))
    if points is not None:
        assert points.shape == expected.shape and np.all(np.isfinite(points))
        changed = np.any(points != expected, axis=1)
        assert changed.sum() <= len(flips)
