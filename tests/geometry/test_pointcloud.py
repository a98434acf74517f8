"""Point-cloud files: round trips and clear errors naming the file."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from steamtwin.geometry.pointcloud import (
    PointCloudError,
    check_point_cloud,
    read_point_cloud,
    write_point_cloud,
)

CLOUD = np.random.default_rng(1).normal(scale=0.02, size=(500, 3))


@pytest.mark.parametrize("suffix", [".ply", ".pcd", ".xyz"])
def test_round_trip(tmp_path, suffix: str) -> None:
    path = tmp_path / f"cloud{suffix}"
    write_point_cloud(CLOUD, path)
    # PCD stores float32: about 10 nm at these coordinates
    np.testing.assert_allclose(read_point_cloud(path), CLOUD, rtol=0, atol=1e-8)


def test_millimetre_files_are_refused_with_a_hint_or_scaled(tmp_path) -> None:
    path = tmp_path / "mm.xyz"
    write_point_cloud(CLOUD * 1000.0, path)
    with pytest.raises(PointCloudError, match=r"mm\.xyz.*millimetres"):
        read_point_cloud(path)
    np.testing.assert_allclose(read_point_cloud(path, unit_scale=1e-3), CLOUD, rtol=1e-8)


def test_bad_files_name_the_file(tmp_path) -> None:
    empty = tmp_path / "empty.ply"
    empty.write_bytes(b"")
    with pytest.raises(PointCloudError, match=r"empty\.ply.*empty"):
        read_point_cloud(empty)
    garbage = tmp_path / "garbage.pcd"
    garbage.write_text("hello\n")
    with pytest.raises(PointCloudError, match=r"garbage\.pcd"):
        read_point_cloud(garbage)
    text = tmp_path / "nan.xyz"
    cloud = CLOUD.copy()
    cloud[7, 2] = np.nan
    np.savetxt(text, cloud)
    with pytest.raises(PointCloudError, match=r"nan\.xyz.*1 of 500.*index 7"):
        read_point_cloud(text)
    line = tmp_path / "line.xyz"
    np.savetxt(line, np.outer(np.linspace(0, 0.1, 300), [1.0, 2.0, 3.0]))
    with pytest.raises(PointCloudError, match=r"line\.xyz.*degenerate"):
        read_point_cloud(line)
    with pytest.raises(PointCloudError, match=r"missing\.ply.*no such file"):
        read_point_cloud(tmp_path / "missing.ply")
    with pytest.raises(PointCloudError, match=r"\.obj"):
        read_point_cloud(tmp_path / "cloud.obj")


@given(scale=st.floats(1e-6, 1e6), count=st.integers(0, 300))
def test_check_accepts_exactly_the_plausible_clouds(scale: float, count: int) -> None:
    points = CLOUD[:count] * scale
    extent = np.linalg.norm(np.ptp(points, axis=0)) if count else 0.0
    plausible = count >= 100 and 1e-3 <= extent <= 10.0
    if plausible:
        assert check_point_cloud(points).shape == (count, 3)
    else:
        with pytest.raises(PointCloudError):
            check_point_cloud(points)
