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
def test_round_trip_is_exact(tmp_path, suffix: str) -> None:
    path = tmp_path / f"cloud{suffix}"
    write_point_cloud(CLOUD, path)
    # PCD stores float32 (about 10 nm at these coordinates); PLY and XYZ keep float64
    expected = CLOUD.astype(np.float32).astype(np.float64) if suffix == ".pcd" else CLOUD
    np.testing.assert_array_equal(read_point_cloud(path), expected)


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
    with pytest.raises(PointCloudError, match=r"nan\.xyz: line 8: element 'point' point 8 "
                                              r"\(1-based\): property 'z' is nan.*1 of 500"):
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


def test_check_names_the_first_non_finite_point_1_based() -> None:
    cloud = CLOUD.copy()
    cloud[[7, 9], 0] = np.inf
    with pytest.raises(PointCloudError, match=r"scan: 2 of 500 points .* point 8, 1-based"):
        check_point_cloud(cloud, "scan")


# --- issue 16, finding 2: short, truncated and non-finite files are refused, never zero-filled


def ply_text(points: np.ndarray, count: int | None = None) -> str:
    """An ASCII PLY of ``points``; vertex k (1-based) is on line 7 + k."""
    header = (f"ply\nformat ascii 1.0\nelement vertex {len(points) if count is None else count}"
              "\nproperty double x\nproperty double y\nproperty double z\nend_header\n")
    return header + "".join(" ".join(f"{v:.17g}" for v in row) + "\n" for row in points)


def test_ascii_ply_reads_exactly(tmp_path) -> None:
    path = tmp_path / "text.ply"
    path.write_text(ply_text(CLOUD).replace("\n", "\r\n"))
    np.testing.assert_array_equal(read_point_cloud(path), CLOUD)


@pytest.mark.parametrize("cut", [2405, 2400])
def test_truncated_binary_view_is_refused(tmp_path, cut: int) -> None:
    path = tmp_path / "view_03.ply"
    write_point_cloud(CLOUD, path)
    path.write_bytes(path.read_bytes()[:-cut])
    complete = (500 * 24 - cut) // 24
    with pytest.raises(PointCloudError, match=(
            rf"view_03\.ply: element 'vertex' promises 500 points of 24 bytes \(12000 bytes\) "
            rf"but only {500 * 24 - cut} bytes follow \({complete} complete points\): the file "
            "is truncated")):
        read_point_cloud(path)


@pytest.mark.parametrize("token", ["inf", "-inf", "nan", "1e999"])
def test_non_finite_value_in_ascii_ply_is_refused_with_its_line(tmp_path, token: str) -> None:
    path = tmp_path / "scan.ply"
    text = ply_text(CLOUD).splitlines(keepends=True)
    text[7 + 42 - 1] = f"{token} 0.01 0.02\n"
    path.write_text("".join(text))
    with pytest.raises(PointCloudError, match=(
            r"scan\.ply: line 49: element 'vertex' point 42 \(1-based\): property 'x' is "
            r"-?(inf|nan), not a finite coordinate \(1 of 500 points are not finite\)")):
        read_point_cloud(path)


def test_header_promising_more_points_than_present_is_refused(tmp_path) -> None:
    text = tmp_path / "more.ply"
    text.write_text(ply_text(CLOUD, count=600))
    with pytest.raises(PointCloudError, match=(
            r"more\.ply: element 'vertex' promises 600 points \(header line 3\) but the file "
            r"ends after 500 of them \(last data line 507\): the file is truncated")):
        read_point_cloud(text)
    binary = tmp_path / "more_binary.ply"
    write_point_cloud(CLOUD, binary)
    binary.write_bytes(binary.read_bytes().replace(b"element vertex 500", b"element vertex 600"))
    with pytest.raises(PointCloudError, match=r"more_binary\.ply: element 'vertex' promises "
                                              r"600 points.*\(500 complete points\)"):
        read_point_cloud(binary)


def test_short_ascii_files_are_refused(tmp_path) -> None:
    path = tmp_path / "short.ply"
    lines = ply_text(CLOUD).splitlines(keepends=True)
    path.write_text("".join([*lines[:11], "0.01 0.02\n", *lines[12:]]))
    with pytest.raises(PointCloudError, match=r"short\.ply: line 12: 2 values where element "
                                              r"'vertex' has 3 \(x y z\)"):
        read_point_cloud(path)
    path.write_text("".join(lines[:-1]))
    with pytest.raises(PointCloudError, match=r"promises 500 points .* ends after 499 of them"):
        read_point_cloud(path)
    path.write_text(ply_text(CLOUD)[:-4])  # cut in the last number: still three values
    with pytest.raises(PointCloudError, match=r"short\.ply: line 507 has no line break at its "
                                              r"end: the file may be cut off"):
        read_point_cloud(path)


def test_more_rows_than_the_header_declares_are_refused(tmp_path) -> None:
    path = tmp_path / "less.ply"
    path.write_text(ply_text(CLOUD, count=400))
    with pytest.raises(PointCloudError, match=r"less\.ply: line 408: 100 data lines after the "
                                              r"last row the header declares \(400 vertex\)"):
        read_point_cloud(path)
    write_point_cloud(CLOUD, path)
    path.write_bytes(path.read_bytes().replace(b"element vertex 500", b"element vertex 400"))
    with pytest.raises(PointCloudError, match=r"less\.ply: 2400 bytes after the last row"):
        read_point_cloud(path)


@pytest.mark.parametrize(("text", "message"), [
    ("", r"the file is empty"),
    ("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
     "property float z\nend_header\n", r"element 'vertex' holds 0 points \(header line 3\)"),
    ("ply\nformat binary_little_endian 1.0\nelement vertex 500\nproperty float x\n"
     "property float y\nproperty float z\nend_header\n",
     r"promises 500 points of 12 bytes \(6000 bytes\) but only 0 bytes follow"),
    ("solid blade\n", r"not a PLY file \(the first line is not 'ply'\)"),
    ("ply\nformat ascii 1.0\nelement vertex 5\n", r"has no 'end_header' line"),
    ("ply\nformat ascii 1.0\nelement vertex 5\nproperty quad x\nend_header\n",
     r"header line 4: unknown property type 'quad'"),
    ("ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
     "property list uchar float z\nend_header\n", r"element 'vertex' has list property 'z'"),
    ("ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
     "end_header\n", r"element 'vertex' has no property 'z'"),
    ("ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float x\nend_header\n",
     r"header line 5: property 'x' declared twice in element 'vertex'"),
    ("ply\nelement vertex 5\nproperty float x\nend_header\n", r"has no 'format' line"),
    ("ply\nformat ascii 1.0\nelement face 5\nend_header\n", r"declares no element 'vertex'"),
    ("ply\nformat ascii 1.0\nelement vertex 5\nelement vertex 5\nend_header\n",
     r"header line 4: element 'vertex' declared twice"),
    ("ply\nformat ascii 1.0\nelement vertex 5\nproperty float\nend_header\n",
     r"header line 4: 'property float' is not 'property <type> <name>'"),
    ("ply\nformat ascii 1.0\nvertex 5\n", r"header line 3: 'vertex 5' is not a PLY header line"),
    ("ply\nformat ascii 1.0\nelement vertex -5\nend_header\n",
     r"header line 3: 'element vertex -5' is not"),
    ("ply\nformat utf8 1.0\nend_header\n", r"header line 2: 'format utf8 1.0' is not one"),
    ("ply\nformat ascii 1.0\nproperty float x\nend_header\n",
     r"header line 3: property before any element"),
    ("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
     "property float z\nend_header\n0 0 0\n0.01 abc 0\n",
     r"line 9: property 'y' of element 'vertex' is 'abc', not a number"),
    ("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
     "property float z\nend_header\n0 0 0\n0.01 1_0 0\n",
     r"line 9: property 'y' of element 'vertex' is '1_0', not a number"),
])
def test_malformed_ply_files_are_refused_clearly(tmp_path, text: str, message: str) -> None:
    path = tmp_path / "bad.ply"
    path.write_text(text)
    with pytest.raises(PointCloudError, match=rf"bad\.ply: .*{message}"):
        read_point_cloud(path)


def test_binary_noise_as_ply_is_refused(tmp_path) -> None:
    path = tmp_path / "noise.ply"
    noise = np.random.default_rng(3).bytes(5000)
    path.write_bytes(noise)
    with pytest.raises(PointCloudError, match=r"noise\.ply: not a PLY file"):
        read_point_cloud(path)
    path.write_bytes(b"ply\n" + noise)
    with pytest.raises(PointCloudError, match=r"noise\.ply: header line \d+ is not ASCII text"):
        read_point_cloud(path)
    path.write_bytes(ply_text(CLOUD).encode()[:300] + b"\xff" + ply_text(CLOUD).encode()[300:])
    with pytest.raises(PointCloudError, match=r"noise\.ply: line \d+: byte 0xff is not ASCII"):
        read_point_cloud(path)


def test_big_endian_ply_with_other_properties_and_faces(tmp_path) -> None:
    vertex = np.dtype([("x", ">f4"), ("red", "u1"), ("y", ">f4"), ("z", ">f4")])
    table = np.zeros(len(CLOUD), vertex)
    for axis, column in zip("xyz", CLOUD.T, strict=True):
        table[axis] = column
    faces = [bytes([3]) + np.array([0, 1, k], ">i4").tobytes() for k in range(2, 12)]
    faces.append(bytes([4]) + np.array([0, 1, 2, 3], ">i4").tobytes())
    header = ("ply\nformat binary_big_endian 1.0\ncomment hand-made\nelement vertex 500\n"
              "property float x\nproperty uchar red\nproperty float y\nproperty float z\n"
              "element face 11\nproperty list uchar int vertex_indices\nend_header\n")
    body = table.tobytes() + b"".join(faces)
    path = tmp_path / "mesh.ply"
    path.write_bytes(header.encode() + body)
    np.testing.assert_array_equal(read_point_cloud(path),
                                  CLOUD.astype(np.float32).astype(np.float64))
    path.write_bytes(header.encode() + body[:-3])
    with pytest.raises(PointCloudError, match=r"mesh\.ply: element 'face' promises 11 rows but "
                                              r"the file ends in row 11: the file is truncated"):
        read_point_cloud(path)


def test_pcd_files_get_the_same_checks(tmp_path) -> None:
    import open3d as o3d

    path = tmp_path / "view.pcd"
    write_point_cloud(CLOUD, path)
    path.write_bytes(path.read_bytes()[:-30])
    with pytest.raises(PointCloudError, match=r"view\.pcd: element 'point' promises 500 points "
                                              r"of 12 bytes \(6000 bytes\) but only 5970 bytes "
                                              r"follow \(497 complete points\)"):
        read_point_cloud(path)
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(CLOUD))
    text = tmp_path / "text.pcd"
    o3d.io.write_point_cloud(str(text), cloud, write_ascii=True)
    np.testing.assert_allclose(read_point_cloud(text), CLOUD, rtol=0, atol=1e-11)
    lines = text.read_text().splitlines(keepends=True)
    assert lines[10] == "DATA ascii\n"
    text.write_text("".join([*lines[:11 + 20], "0.01 inf 0.02\n", *lines[11 + 21:]]))
    with pytest.raises(PointCloudError, match=r"text\.pcd: line 32: element 'point' point 21 "
                                              r"\(1-based\): property 'y' is inf"):
        read_point_cloud(text)
    text.write_text("".join(lines[:-3]))
    with pytest.raises(PointCloudError, match=r"promises 500 points \(PCD header\) but the "
                                              r"file holds 497"):
        read_point_cloud(text)
    text.write_text("".join(lines).replace("POINTS 500", "POINTS 400"))
    with pytest.raises(PointCloudError, match=r"POINTS 400 differs from WIDTH × HEIGHT = 500"):
        read_point_cloud(text)
    text.write_text("".join(lines).replace("500", "0"))
    with pytest.raises(PointCloudError, match=r"declares 0 points"):
        read_point_cloud(text)
    packed = tmp_path / "packed.pcd"
    o3d.io.write_point_cloud(str(packed), cloud, compressed=True)
    np.testing.assert_array_equal(read_point_cloud(packed),
                                  CLOUD.astype(np.float32).astype(np.float64))
    packed.write_bytes(packed.read_bytes()[:-7])
    with pytest.raises(PointCloudError, match=r"packed\.pcd: the compressed block holds \d+ "
                                              r"bytes but \d+ follow its sizes: the file is "
                                              "truncated"):
        read_point_cloud(packed)


def test_xyz_files_get_the_same_checks(tmp_path) -> None:
    path = tmp_path / "scan.xyz"
    write_point_cloud(CLOUD, path)
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("# x y z in m\n" + "".join([*lines[:9], "0.01 0.02 -inf\n", *lines[10:]]))
    with pytest.raises(PointCloudError, match=r"scan\.xyz: line 11: element 'point' point 10 "
                                              r"\(1-based\): property 'z' is -inf"):
        read_point_cloud(path)
    path.write_text("".join([*lines[:4], "0.01 0.02\n", *lines[5:]]))
    with pytest.raises(PointCloudError, match=r"scan\.xyz: line 5: 2 values where element "
                                              r"'point' has 3 \(x y z\)"):
        read_point_cloud(path)
    path.write_text("".join(lines)[:-3])
    with pytest.raises(PointCloudError, match=r"line 500 has no line break"):
        read_point_cloud(path)
    path.write_text("".join(lines).replace(" ", "\t", 5).replace(" ", "\r", 1))
    np.testing.assert_array_equal(read_point_cloud(path), CLOUD)  # any whitespace separates
    path.write_text("# only a comment\n")
    with pytest.raises(PointCloudError, match=r"scan\.xyz: the file holds no points"):
        read_point_cloud(path)


@pytest.mark.parametrize("scale", [0.0, -1e-3, np.nan, np.inf])
def test_unit_scale_must_be_a_positive_factor(tmp_path, scale: float) -> None:
    path = tmp_path / "cloud.ply"
    write_point_cloud(CLOUD, path)
    with pytest.raises(PointCloudError, match=r"cloud\.ply: unit_scale must be a positive"):
        read_point_cloud(path, unit_scale=scale)


PCD_HEADER = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
              "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n")


@pytest.mark.parametrize(("old", "new", "message"), [
    ("", "", r"only 2 points"),  # the base file is well-formed
    ("VERSION 0.7\n", "hello\n", r"header line 2: 'hello' is not a PCD header line"),
    ("VERSION 0.7\n", "WIDTH 2\n", r"header line 7: WIDTH given twice"),
    ("SIZE 4 4 4\n", "", r"the PCD header has no SIZE line"),
    ("SIZE 4 4 4", "SIZE 4 4", r"FIELDS, SIZE, TYPE and COUNT differ in length \(3, 2, 3, 3\)"),
    ("TYPE F F F", "TYPE F F Q", r"field 'z': TYPE Q SIZE 4 COUNT 1 is not a supported field"),
    ("SIZE 4 4 4", "SIZE 4 4 3", r"field 'z': TYPE F SIZE 3 COUNT 1 is not a supported"),
    ("COUNT 1 1 1", "COUNT 1 2 1", r"fields x, y and z must have COUNT 1"),
    ("FIELDS x y z", "FIELDS x y w", r"element 'point' has no property 'z'"),
    ("WIDTH 2\nHEIGHT 1\nPOINTS 2\n", "", r"has neither POINTS nor WIDTH"),
    ("WIDTH 2", "WIDTH two", r"PCD WIDTH must be one integer >= 0, got 'two'"),
    ("DATA ascii", "DATA zipped", r"PCD DATA 'zipped' is not ascii, binary or binary_comp"),
    ("DATA ascii\n", "DATA ascii\n0 0 0\n", r"line 13: 1 data lines after the 2 points"),
    ("DATA ascii\n", "", r"header line 10: '0 0 0' is not a PCD header line"),
])
def test_malformed_pcd_files_are_refused_clearly(tmp_path, old: str, new: str,
                                                  message: str) -> None:
    path = tmp_path / "bad.pcd"
    path.write_text(PCD_HEADER.replace(old, new, 1) + "0 0 0\n0.01 0.02 0.03\n")
    with pytest.raises(PointCloudError, match=rf"bad\.pcd: .*{message}"):
        read_point_cloud(path)


def test_pcd_padding_fields_and_body_sizes(tmp_path) -> None:
    import open3d as o3d

    table = np.zeros(len(CLOUD), [("x", "<f8"), ("pad", "u1", (3,)), ("y", "<f8"), ("z", "<f8")])
    for axis, column in zip("xyz", CLOUD.T, strict=True):
        table[axis] = column
    header = (b"FIELDS x _ y z\nSIZE 8 1 8 8\nTYPE F U F F\nCOUNT 1 3 1 1\nWIDTH 500\n"
              b"DATA binary\n")
    path = tmp_path / "padded.pcd"
    path.write_bytes(header + table.tobytes())
    np.testing.assert_array_equal(read_point_cloud(path), CLOUD)
    path.write_bytes(header + table.tobytes() + b"\n")
    with pytest.raises(PointCloudError, match=r"padded\.pcd: 1 bytes after the 500 points"):
        read_point_cloud(path)
    packed = tmp_path / "packed.pcd"
    o3d.io.write_point_cloud(str(packed), o3d.geometry.PointCloud(
        o3d.utility.Vector3dVector(CLOUD)), compressed=True)
    data = packed.read_bytes()
    body = data.index(b"DATA binary_compressed\n") + len(b"DATA binary_compressed\n")
    sizes = np.frombuffer(data, "<u4", count=2, offset=body)
    wrong = np.array([sizes[0], sizes[1] - 12], "<u4").tobytes()
    packed.write_bytes(data[:body] + wrong + data[body + 8:])
    with pytest.raises(PointCloudError, match=r"decodes to 5988 bytes, but the header's 500 "
                                              r"points of 12 bytes need 6000"):
        read_point_cloud(packed)
    garbled = data[:body + 8] + bytes([255]) * (len(data) - body - 8)
    packed.write_bytes(garbled)
    with pytest.raises(PointCloudError, match=r"packed\.pcd: the compressed block could not be "
                                              r"decoded: 0 of the header's 500 points read"):
        read_point_cloud(packed)
    packed.write_bytes(data[:body + 5])
    with pytest.raises(PointCloudError, match=r"ends before the compressed block's sizes"):
        read_point_cloud(packed)


def test_ply_list_and_line_errors(tmp_path) -> None:
    path = tmp_path / "lists.ply"
    path.write_text("ply\nply\nformat ascii 1.0\nend_header\n")
    with pytest.raises(PointCloudError, match=r"header line 2: a second 'ply' line"):
        read_point_cloud(path)
    path.write_text("ply\nformat ascii 1.0\nelement face 1\nproperty list float int v\n"
                    "end_header\n")
    with pytest.raises(PointCloudError, match=r"header line 4: a list's length must have an "
                                              r"integer type, not 'float'"):
        read_point_cloud(path)
    header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 500\nproperty double x\n"
              b"property double y\nproperty double z\nelement face 2\n"
              b"property list char int vertex_indices\nend_header\n")
    faces = bytes([3]) + np.array([0, 1, 2], "<i4").tobytes() + bytes([255])
    path.write_bytes(header + CLOUD.tobytes() + faces)
    with pytest.raises(PointCloudError, match=r"lists\.ply: element 'face' row 2: list "
                                              r"'vertex_indices' has a negative length -1"):
        read_point_cloud(path)
    path.write_bytes(header + CLOUD.tobytes() + faces[:-1])
    with pytest.raises(PointCloudError, match=r"element 'face' promises 2 rows but the file "
                                              r"ends in row 2"):
        read_point_cloud(path)


def test_binary_ply_checks_fixed_size_elements_after_the_vertices(tmp_path) -> None:
    header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 500\nproperty double x\n"
              b"property double y\nproperty double z\nelement camera 2\nproperty float f\n"
              b"end_header\n")
    path = tmp_path / "camera.ply"
    path.write_bytes(header + CLOUD.tobytes() + bytes(8))
    np.testing.assert_array_equal(read_point_cloud(path), CLOUD)
    path.write_bytes(header + CLOUD.tobytes() + bytes(5))
    with pytest.raises(PointCloudError, match=r"camera\.ply: element 'camera' promises 2 rows "
                                              r"of 4 bytes \(8 bytes\) but only 5 bytes follow "
                                              r"\(1 complete rows\)"):
        read_point_cloud(path)


def test_an_unreadable_file_is_named(tmp_path, monkeypatch) -> None:
    path = tmp_path / "locked.ply"
    write_point_cloud(CLOUD, path)

    def refuse(self):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(type(path), "read_bytes", refuse)
    with pytest.raises(PointCloudError, match=r"locked\.ply: cannot read the file: Permission "
                                              "denied"):
        read_point_cloud(path)
