"""Reading and writing point clouds (PLY, PCD, XYZ), with checks that name the file.

Kept as one module because the three readers share the header scanning, the row parsing and the
error messages that name file, line and element; apart they would repeat them.

Clouds are (n, 3) float64 arrays in metres. A file in millimetres is read with
``unit_scale=1e-3``; a cloud whose size is implausible for a turbine part in metres is refused
with a hint rather than silently misread.

The PLY and PCD readers parse the header themselves and read the body with numpy, because
open3d's reader fills points it cannot read (a truncated body, ``inf`` in ASCII) with zeros or
uninitialised memory and still returns the header's count. A file is refused when its body
holds fewer or more rows than the header promises, a value is not a number, or a coordinate is
not finite; the message names the file, the element and property, the counts and, in text
files, the 1-based line. Only compressed PCD bodies are decoded by open3d, after the sizes in
the body were checked, and its result is checked against the header's count.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from steamtwin.errors import GeometryAreaError

SUFFIXES = (".ply", ".pcd", ".xyz")
#: Plausible bounding-box diagonal of a scanned turbine part, m (a 1 mm chip to a 10 m casing).
MIN_EXTENT, MAX_EXTENT = 1e-3, 10.0
MIN_POINTS = 100

#: PLY property types (Turk's PLY format: both the 1994 names and the sized aliases).
PLY_TYPES = {"char": "i1", "uchar": "u1", "short": "i2", "ushort": "u2", "int": "i4",
             "uint": "u4", "float": "f4", "double": "f8", "int8": "i1", "uint8": "u1",
             "int16": "i2", "uint16": "u2", "int32": "i4", "uint32": "u4", "float32": "f4",
             "float64": "f8"}
PLY_FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}
#: PCD field types by (TYPE, SIZE) (PCL's PCD v0.7 file format).
PCD_TYPES = {("F", 4): "f4", ("F", 8): "f8", ("I", 1): "i1", ("I", 2): "i2", ("I", 4): "i4",
             ("I", 8): "i8", ("U", 1): "u1", ("U", 2): "u2", ("U", 4): "u4", ("U", 8): "u8"}
AXES = ("x", "y", "z")


class PointCloudError(GeometryAreaError):
    """An unreadable, short, empty, non-finite, degenerate or implausibly scaled point cloud."""


def read_point_cloud(path: str | Path, unit_scale: float = 1.0) -> np.ndarray:
    """Read the points (n, 3) of a PLY, PCD or XYZ file, times ``unit_scale`` (to metres).

    Raises :class:`PointCloudError` naming the file when it is missing, unreadable, empty,
    truncated or longer than its header says, holds a value that is not a number or a NaN/inf
    coordinate (with the element, property and, in text files, the 1-based line), is degenerate
    (fewer than 100 points, all on a line) or its bounding box diagonal is outside 1 mm – 10 m
    (wrong units).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise PointCloudError(f"{path}: unknown point-cloud format {suffix!r}; "
                              f"expected one of {', '.join(SUFFIXES)}")
    if not (np.isfinite(unit_scale) and unit_scale > 0.0):
        raise PointCloudError(f"{path}: unit_scale must be a positive factor to metres "
                              f"(got {unit_scale})")
    if not path.is_file():
        raise PointCloudError(f"{path}: no such file")
    try:
        data = path.read_bytes()
    except OSError as error:
        raise PointCloudError(f"{path}: cannot read the file: {error.strerror}") from None
    if not data:
        raise PointCloudError(f"{path}: the file is empty")
    reader = {".ply": _read_ply, ".pcd": _read_pcd, ".xyz": _read_xyz}[suffix]
    return check_point_cloud(reader(path, data) * unit_scale, str(path))


# --- text bodies ---------------------------------------------------------------------------------


def _text_lines(path: Path, body: bytes, first_line: int) -> list[tuple[int, str]]:
    """The non-blank lines of a text body with their 1-based line numbers in the file; the
    body must end with a line break."""
    try:
        text = body.decode("ascii")
    except UnicodeDecodeError as error:
        line = first_line + body[:error.start].count(b"\n")
        raise PointCloudError(f"{path}: line {line}: byte 0x{body[error.start]:02x} is not "
                              "ASCII text (a text point cloud holds numbers only)") from None
    lines = text.split("\n")
    if lines[-1].strip():
        # a file cut in its last number still has the row's count of values: refuse it
        raise PointCloudError(f"{path}: line {first_line + len(lines) - 1} has no line break "
                              "at its end: the file may be cut off (add one if it is whole)")
    return [(first_line + k, line) for k, line in enumerate(lines) if line.strip()]


def _parse_rows(path: Path, lines: list[tuple[int, str]], names: list[str],
                element: str) -> np.ndarray:
    """Rows of whitespace-separated numbers, one row a line, one value per name → (n, k)."""
    try:  # numpy's C parser first; the loop below only runs to find what it refused
        values = np.loadtxt(io.StringIO("\n".join(line.strip() for _, line in lines)),
                            dtype=np.float64, comments=None, ndmin=2)
        if values.shape == (len(lines), len(names)):
            return values
    except ValueError:
        pass
    rows = []
    for number, line in lines:
        tokens = line.split()
        if len(tokens) != len(names):
            raise PointCloudError(f"{path}: line {number}: {len(tokens)} values where element "
                                  f"{element!r} has {len(names)} ({' '.join(names)})")
        for name, token in zip(names, tokens, strict=True):
            if not _is_number(token):
                raise PointCloudError(f"{path}: line {number}: property {name!r} of element "
                                      f"{element!r} is {token!r}, not a number")
        rows.append(tokens)
    # every token is a number, only separated by whitespace numpy's parser does not split at
    return np.array(rows, dtype=np.float64)


def _is_number(token: str) -> bool:
    """Whether numpy reads ``token`` as a number (inf and nan included) and it holds no '_'
    (numpy and Python read "1_0" as 10; no number in these formats holds one)."""
    try:
        np.float64(token)
    except ValueError:
        return False
    return "_" not in token


def _require_finite(path: Path, xyz: np.ndarray, element: str,
                    lines: list[tuple[int, str]] | None = None) -> np.ndarray:
    """``xyz`` if every coordinate is finite, else an error naming the first bad one."""
    bad = ~np.isfinite(xyz)
    if np.any(bad):
        row, axis = np.unravel_index(int(np.argmax(bad)), bad.shape)
        where = "" if lines is None else f"line {lines[row][0]}: "
        count = int(np.any(bad, axis=1).sum())
        raise PointCloudError(f"{path}: {where}element {element!r} point {row + 1} (1-based): "
                              f"property {AXES[axis]!r} is {xyz[row, axis]}, not a finite "
                              f"coordinate ({count} of {len(xyz)} points are not finite)")
    return xyz


def _axes(path: Path, names: list[str], element: str) -> list[int]:
    """Positions of x, y, z among an element's properties."""
    missing = [axis for axis in AXES if axis not in names]
    if missing:
        raise PointCloudError(f"{path}: element {element!r} has no property "
                              f"{' '.join(map(repr, missing))} (needs x, y and z)")
    return [names.index(axis) for axis in AXES]


def _header(path: Path, data: bytes, kind: str, keywords: tuple[str, ...],
            last: str) -> tuple[list[tuple[int, list[str]]], int]:
    """The header of a PLY or PCD file: (1-based line number, tokens) of each line up to and
    including the one starting with ``last``, and the offset of the body. Blank lines and
    lines starting with '#' are skipped; any other line must start with one of ``keywords``."""
    lines, position, number = [], 0, 0
    while True:
        end = data.find(b"\n", position)
        raw = data[position:] if end < 0 else data[position:end]
        position = len(data) if end < 0 else end + 1
        number += 1
        try:
            tokens = raw.decode("ascii").split()
        except UnicodeDecodeError:
            raise PointCloudError(f"{path}: header line {number} is not ASCII text "
                                  f"(not a {kind} file?)") from None
        if tokens and not tokens[0].startswith("#"):
            if tokens[0] not in keywords:
                raise PointCloudError(f"{path}: header line {number}: {' '.join(tokens)[:40]!r} "
                                      f"is not a {kind} header line (expected one of "
                                      f"{', '.join(keywords)})")
            lines.append((number, tokens))
            if tokens[0] == last:
                return lines, position
        if end < 0:
            raise PointCloudError(f"{path}: the {kind} header has no {last!r} line "
                                  f"(not a {kind} file, or cut off in the header)")


# --- PLY -----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _PlyProperty:
    name: str
    dtype: str  # numpy type code without byte order; of the items for a list
    count_dtype: str | None = None  # numpy type code of a list's length, None for a scalar


@dataclass(frozen=True)
class _PlyElement:
    name: str
    count: int
    line: int  # 1-based header line of its declaration
    properties: list[_PlyProperty]

    def row_dtype(self, byte_order: str) -> np.dtype:
        return np.dtype([(f"p{k}", byte_order + p.dtype) for k, p in enumerate(self.properties)])


def _ply_type(path: Path, number: int, name: str) -> str:
    if name not in PLY_TYPES:
        raise PointCloudError(f"{path}: header line {number}: unknown property type {name!r} "
                              f"(expected one of {', '.join(PLY_TYPES)})")
    return PLY_TYPES[name]


def _ply_header(path: Path, data: bytes) -> tuple[str, list[_PlyElement], int, int]:
    """(format, elements, body offset, lines in the header) of a PLY file."""
    if data.partition(b"\n")[0].strip() != b"ply":
        raise PointCloudError(f"{path}: not a PLY file (the first line is not 'ply')")
    lines, body_offset = _header(path, data, "PLY", ("ply", "format", "comment", "obj_info",
                                                     "element", "property", "end_header"),
                                 "end_header")
    file_format, elements = None, []
    for number, tokens in lines[1:]:
        keyword, line = tokens[0], " ".join(tokens)
        if keyword in ("comment", "obj_info", "end_header"):
            continue
        if keyword == "ply":
            raise PointCloudError(f"{path}: header line {number}: a second 'ply' line")
        if keyword == "format":
            if len(tokens) != 3 or tokens[1] not in PLY_FORMATS or file_format is not None:
                raise PointCloudError(f"{path}: header line {number}: {line!r} is not one "
                                      f"'format <{'|'.join(PLY_FORMATS)}> 1.0' line")
            file_format = tokens[1]
        elif keyword == "element":
            if len(tokens) != 3 or not tokens[2].isdigit():
                raise PointCloudError(f"{path}: header line {number}: {line!r} is not "
                                      "'element <name> <count>' with a count >= 0")
            if any(e.name == tokens[1] for e in elements):
                raise PointCloudError(f"{path}: header line {number}: element {tokens[1]!r} "
                                      "declared twice")
            elements.append(_PlyElement(tokens[1], int(tokens[2]), number, []))
        else:
            if not elements:
                raise PointCloudError(f"{path}: header line {number}: property before any "
                                      "element")
            if len(tokens) == 5 and tokens[1] == "list":
                count_dtype = _ply_type(path, number, tokens[2])
                if count_dtype[0] == "f":
                    raise PointCloudError(f"{path}: header line {number}: a list's length "
                                          f"must have an integer type, not {tokens[2]!r}")
                prop = _PlyProperty(tokens[4], _ply_type(path, number, tokens[3]), count_dtype)
            elif len(tokens) == 3:
                prop = _PlyProperty(tokens[2], _ply_type(path, number, tokens[1]))
            else:
                raise PointCloudError(f"{path}: header line {number}: {line!r} is not "
                                      "'property <type> <name>' or 'property list <count "
                                      "type> <item type> <name>'")
            if any(p.name == prop.name for p in elements[-1].properties):
                raise PointCloudError(f"{path}: header line {number}: property "
                                      f"{prop.name!r} declared twice in element "
                                      f"{elements[-1].name!r}")
            elements[-1].properties.append(prop)
    if file_format is None:
        raise PointCloudError(f"{path}: the PLY header has no 'format' line")
    vertex = next((e for e in elements if e.name == "vertex"), None)
    if vertex is None:
        raise PointCloudError(f"{path}: the PLY header declares no element 'vertex'")
    if vertex.count == 0:
        raise PointCloudError(f"{path}: element 'vertex' holds 0 points (header line "
                              f"{vertex.line}): the file has no points")
    lists = [p.name for p in vertex.properties if p.count_dtype is not None]
    if lists:
        raise PointCloudError(f"{path}: element 'vertex' has list property {lists[0]!r}; a "
                              "point cloud's vertices must have fixed-size rows")
    _axes(path, [p.name for p in vertex.properties], "vertex")
    return file_format, elements, body_offset, lines[-1][0]


def _read_ply(path: Path, data: bytes) -> np.ndarray:
    file_format, elements, body_offset, header_lines = _ply_header(path, data)
    body = data[body_offset:]
    if file_format == "ascii":
        return _read_ply_ascii(path, body, elements, header_lines + 1)
    return _read_ply_binary(path, body, elements, PLY_FORMATS[file_format])


def _read_ply_ascii(path: Path, body: bytes, elements: list[_PlyElement],
                    first_line: int) -> np.ndarray:
    lines = _text_lines(path, body, first_line)
    start = 0
    for element in elements:
        rows = lines[start:start + element.count]
        if len(rows) < element.count:
            last = f" (last data line {lines[-1][0]})" if lines else ""
            rows_name = "points" if element.name == "vertex" else "rows"
            raise PointCloudError(f"{path}: element {element.name!r} promises {element.count} "
                                  f"{rows_name} (header line {element.line}) but the file ends "
                                  f"after {len(rows)} of them{last}: the file is truncated")
        if element.name == "vertex":
            names = [p.name for p in element.properties]
            values = _parse_rows(path, rows, names, "vertex")
            xyz = _require_finite(path, values[:, _axes(path, names, "vertex")], "vertex", rows)
        start += element.count
    if start < len(lines):
        declared = ", ".join(f"{e.count} {e.name}" for e in elements)
        raise PointCloudError(f"{path}: line {lines[start][0]}: {len(lines) - start} data lines "
                              f"after the last row the header declares ({declared}); is a "
                              "count in the header too small?")
    return xyz


def _read_ply_binary(path: Path, body: bytes, elements: list[_PlyElement],
                     byte_order: str) -> np.ndarray:
    offset = 0
    for element in elements:
        if element.name == "vertex":
            row = element.row_dtype(byte_order)
            _require_rows(path, body, offset, element.count, row.itemsize, "vertex")
            table = np.frombuffer(body, dtype=row, count=element.count, offset=offset)
            names = [p.name for p in element.properties]
            xyz = np.column_stack([table[f"p{k}"].astype(np.float64)
                                   for k in _axes(path, names, "vertex")])
            xyz = _require_finite(path, xyz, "vertex")
            offset += element.count * row.itemsize
        else:
            offset = _skip_binary_element(path, body, offset, element, byte_order)
    if offset != len(body):
        declared = ", ".join(f"{e.count} {e.name}" for e in elements)
        raise PointCloudError(f"{path}: {len(body) - offset} bytes after the last row the "
                              f"header declares ({declared}); is a count in the header too "
                              "small?")
    return xyz


def _require_rows(path: Path, body: bytes, offset: int, count: int, row_size: int,
                  element: str) -> None:
    """Refuse a binary body that ends before ``count`` rows of ``element`` from ``offset``."""
    needed, available = count * row_size, len(body) - offset
    if needed > available:
        rows = "points" if element in ("vertex", "point") else "rows"
        raise PointCloudError(f"{path}: element {element!r} promises {count} {rows} of "
                              f"{row_size} bytes ({needed} bytes) but only {available} bytes "
                              f"follow ({available // row_size} complete {rows}): the file is "
                              "truncated")


def _skip_binary_element(path: Path, body: bytes, offset: int, element: _PlyElement,
                         byte_order: str) -> int:
    """Offset after the rows of an element that is not the vertices (e.g. faces)."""
    if all(p.count_dtype is None for p in element.properties):
        row_size = element.row_dtype(byte_order).itemsize
        _require_rows(path, body, offset, element.count, row_size, element.name)
        return offset + element.count * row_size
    for row in range(element.count):
        for prop in element.properties:
            if prop.count_dtype is None:
                offset += np.dtype(prop.dtype).itemsize
                continue
            count_dtype = np.dtype(byte_order + prop.count_dtype)
            if offset + count_dtype.itemsize > len(body):
                offset += count_dtype.itemsize
                break
            length = int(np.frombuffer(body, count_dtype, count=1, offset=offset)[0])
            if length < 0:
                raise PointCloudError(f"{path}: element {element.name!r} row {row + 1}: list "
                                      f"{prop.name!r} has a negative length {length}")
            offset += count_dtype.itemsize + length * np.dtype(prop.dtype).itemsize
        if offset > len(body):
            raise PointCloudError(f"{path}: element {element.name!r} promises "
                                  f"{element.count} rows but the file ends in row {row + 1}: "
                                  "the file is truncated")
    return offset


# --- PCD -----------------------------------------------------------------------------------------


def _pcd_header(path: Path, data: bytes) -> tuple[dict[str, list[str]], int, int]:
    """(fields by keyword, body offset, lines in the header) of a PCD file."""
    keywords = ("VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT",
                "POINTS", "DATA")
    lines, body_offset = _header(path, data, "PCD", keywords, "DATA")
    header: dict[str, list[str]] = {}
    for number, tokens in lines:
        if tokens[0] in header:
            raise PointCloudError(f"{path}: header line {number}: {tokens[0]} given twice")
        header[tokens[0]] = tokens[1:]
    return header, body_offset, lines[-1][0]


def _pcd_count(path: Path, header: dict[str, list[str]], key: str) -> int | None:
    if key not in header:
        return None
    values = header[key]
    if len(values) != 1 or not values[0].isdigit():
        raise PointCloudError(f"{path}: PCD {key} must be one integer >= 0, got "
                              f"{' '.join(values)!r}")
    return int(values[0])


def _read_pcd(path: Path, data: bytes) -> np.ndarray:
    header, body_offset, header_lines = _pcd_header(path, data)
    for key in ("FIELDS", "SIZE", "TYPE"):
        if key not in header:
            raise PointCloudError(f"{path}: the PCD header has no {key} line")
    names = header["FIELDS"]
    counts = header.get("COUNT", ["1"] * len(names))
    if not (len(header["SIZE"]) == len(header["TYPE"]) == len(counts) == len(names)):
        raise PointCloudError(f"{path}: PCD FIELDS, SIZE, TYPE and COUNT differ in length "
                              f"({len(names)}, {len(header['SIZE'])}, {len(header['TYPE'])}, "
                              f"{len(counts)})")
    fields = []
    for name, size, kind, count in zip(names, header["SIZE"], header["TYPE"], counts,
                                       strict=True):
        key = (kind, int(size) if size.isdigit() else -1)
        if key not in PCD_TYPES or not count.isdigit() or int(count) < 1:
            raise PointCloudError(f"{path}: PCD field {name!r}: TYPE {kind} SIZE {size} COUNT "
                                  f"{count} is not a supported field (F 4/8, I or U 1/2/4/8, "
                                  "COUNT >= 1)")
        fields.append((name, PCD_TYPES[key], int(count)))
    axes = _axes(path, names, "point")
    if any(fields[k][2] != 1 for k in axes):
        raise PointCloudError(f"{path}: PCD fields x, y and z must have COUNT 1")
    width, height = _pcd_count(path, header, "WIDTH"), _pcd_count(path, header, "HEIGHT")
    points = _pcd_count(path, header, "POINTS")
    if width is not None:
        organised = width * (1 if height is None else height)
        if points is not None and points != organised:
            raise PointCloudError(f"{path}: PCD POINTS {points} differs from WIDTH × HEIGHT "
                                  f"= {organised}")
        points = organised
    if points is None:
        raise PointCloudError(f"{path}: the PCD header has neither POINTS nor WIDTH")
    if points == 0:
        raise PointCloudError(f"{path}: the PCD header declares 0 points: the file has no "
                              "points")
    storage = header["DATA"]
    body = data[body_offset:]
    if storage == ["ascii"]:
        columns = [name if count == 1 else f"{name}[{k}]"
                   for name, _, count in fields for k in range(count)]
        lines = _text_lines(path, body, header_lines + 1)
        rows = lines[:points]
        if len(rows) < points:
            raise PointCloudError(f"{path}: element 'point' promises {points} points (PCD "
                                  f"header) but the file holds {len(rows)}: the file is "
                                  "truncated")
        if len(lines) > points:
            raise PointCloudError(f"{path}: line {lines[points][0]}: {len(lines) - points} "
                                  f"data lines after the {points} points the header declares")
        values = _parse_rows(path, rows, columns, "point")
        return _require_finite(path, values[:, [columns.index(a) for a in AXES]], "point",
                               rows)
    row = np.dtype([(f"f{k}", "<" + dtype, (count,)) if count > 1 else (f"f{k}", "<" + dtype)
                    for k, (_, dtype, count) in enumerate(fields)])
    if storage == ["binary"]:
        _require_rows(path, body, 0, points, row.itemsize, "point")
        if len(body) > points * row.itemsize:
            raise PointCloudError(f"{path}: {len(body) - points * row.itemsize} bytes after "
                                  f"the {points} points the header declares")
        table = np.frombuffer(body, dtype=row, count=points)
        xyz = np.column_stack([table[f"f{k}"].astype(np.float64) for k in axes])
        return _require_finite(path, xyz, "point")
    if storage == ["binary_compressed"]:
        return _read_pcd_compressed(path, body, points, row.itemsize)
    raise PointCloudError(f"{path}: PCD DATA {' '.join(storage)!r} is not ascii, binary or "
                          "binary_compressed")


def _read_pcd_compressed(path: Path, body: bytes, points: int, row_size: int) -> np.ndarray:
    """Points of an LZF-compressed PCD body, decoded by open3d after its sizes were checked."""
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    if len(body) < 8:
        raise PointCloudError(f"{path}: the file ends before the compressed block's sizes")
    compressed, uncompressed = (int(v) for v in np.frombuffer(body, "<u4", count=2))
    if uncompressed != points * row_size:
        raise PointCloudError(f"{path}: the compressed block decodes to {uncompressed} bytes, "
                              f"but the header's {points} points of {row_size} bytes need "
                              f"{points * row_size}")
    if len(body) != 8 + compressed:
        raise PointCloudError(f"{path}: the compressed block holds {compressed} bytes but "
                              f"{len(body) - 8} follow its sizes: the file is "
                              f"{'truncated' if len(body) < 8 + compressed else 'too long'}")
    with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        cloud = o3d.io.read_point_cloud(str(path), format="pcd", remove_nan_points=False,
                                        remove_infinite_points=False)
    xyz = np.asarray(cloud.points, dtype=np.float64)
    if len(xyz) != points:
        raise PointCloudError(f"{path}: the compressed block could not be decoded: "
                              f"{len(xyz)} of the header's {points} points read")
    return _require_finite(path, xyz, "point")


# --- XYZ -----------------------------------------------------------------------------------------


def _read_xyz(path: Path, data: bytes) -> np.ndarray:
    """x y z [more columns] per line; '#' starts a comment. No header, so no count to check."""
    lines = [(number, line.split("#", 1)[0]) for number, line in _text_lines(path, data, 1)]
    lines = [(number, line) for number, line in lines if line.strip()]
    if not lines:
        raise PointCloudError(f"{path}: the file holds no points")
    width = len(lines[0][1].split())
    if width < 3:
        raise PointCloudError(f"{path}: line {lines[0][0]}: expected at least 3 columns "
                              f"(x y z), got {width}")
    names = [*AXES, *(f"column {k + 1}" for k in range(3, width))]
    values = _parse_rows(path, lines, names, "point")
    return _require_finite(path, values[:, :3], "point", lines)


# --- arrays and writing --------------------------------------------------------------------------


def check_point_cloud(points: np.ndarray, source: str = "point cloud") -> np.ndarray:
    """Validate an (n, 3) cloud in metres; return it as float64 or raise naming ``source``."""
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise PointCloudError(f"{source}: expected an (n, 3) array of points, got {points.shape}")
    if len(points) == 0:
        raise PointCloudError(f"{source}: the cloud is empty")
    bad = ~np.all(np.isfinite(points), axis=1)
    if np.any(bad):
        raise PointCloudError(f"{source}: {int(bad.sum())} of {len(points)} points have NaN or "
                              f"infinite coordinates (first: point {int(np.argmax(bad)) + 1}, "
                              "1-based)")
    if len(points) < MIN_POINTS:
        raise PointCloudError(f"{source}: only {len(points)} points (need >= {MIN_POINTS})")
    with np.errstate(over="ignore"):  # a diagonal beyond 1e308 m is inf: refused below
        extent = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    if extent < MIN_EXTENT or extent > MAX_EXTENT:
        hint = (" — is the file in millimetres? read it with unit_scale=1e-3"
                if MAX_EXTENT < extent <= 1e4 else "")
        raise PointCloudError(f"{source}: bounding-box diagonal {extent:.4g} m is outside the "
                              f"plausible {MIN_EXTENT:g}–{MAX_EXTENT:g} m{hint}")
    centred = points - points.mean(axis=0)
    singular = np.linalg.svd(centred[:: max(1, len(points) // 20000)], compute_uv=False)
    if singular[1] < 1e-6 * singular[0]:
        raise PointCloudError(f"{source}: degenerate cloud, all points lie on a line")
    return points


def write_point_cloud(points: np.ndarray, path: str | Path) -> None:
    """Write an (n, 3) cloud (m) as binary PLY (float64), binary PCD (float32) or text XYZ
    (17 significant digits: read back exactly), by the suffix."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise PointCloudError(f"{path}: unknown point-cloud format {suffix!r}")
    points = np.asarray(points, dtype=np.float64)
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".xyz":
        np.savetxt(path, points, fmt="%.17g")
        return
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        ok = o3d.io.write_point_cloud(str(path), cloud, write_ascii=False)
    if not ok:
        raise PointCloudError(f"{path}: open3d could not write the file")
