"""Point clouds on disk: ``.ply``, ``.pcd``, ``.npy`` and ``.xyz``, read into (N, 3) float64 metres.

Readers (numpy only):

- PLY: ``ascii``, ``binary_little_endian`` and ``binary_big_endian``; the ``vertex`` element's
  ``x y z`` properties of any numeric type. Other elements (faces, ...) are skipped; in binary
  files an element with list properties may only come after the vertices.
- PCD: ``DATA ascii`` and ``DATA binary`` with ``x y z`` fields (``binary_compressed`` is refused
  with a hint).
- NPY: an (N, 3) numeric array, or a structured array with ``x``, ``y``, ``z`` fields.
- XYZ: text, one point per line, the first three whitespace- or comma-separated columns
  (further columns such as normals or colours are ignored), ``#`` comments.

Every reader refuses, with a :class:`CloudFormatError` naming the file and the problem, a file
it cannot parse, a cloud without points, and points with NaN or inf coordinates.
:func:`write_cloud` writes the same formats (for tests and for exporting clouds).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: File suffixes the readers understand.
CLOUD_SUFFIXES = (".ply", ".pcd", ".npy", ".xyz")

_PLY_TYPES = {
    "char": "i1",
    "int8": "i1",
    "uchar": "u1",
    "uint8": "u1",
    "short": "i2",
    "int16": "i2",
    "ushort": "u2",
    "uint16": "u2",
    "int": "i4",
    "int32": "i4",
    "uint": "u4",
    "uint32": "u4",
    "float": "f4",
    "float32": "f4",
    "double": "f8",
    "float64": "f8",
}
_PCD_TYPES = {("F", 4): "f4", ("F", 8): "f8", ("I", 1): "i1", ("I", 2): "i2", ("I", 4): "i4"}
_PCD_TYPES |= {("I", 8): "i8", ("U", 1): "u1", ("U", 2): "u2", ("U", 4): "u4", ("U", 8): "u8"}


class CloudFormatError(ValueError):
    """A cloud file that cannot be read, or whose points are unusable."""


def _finish(points: NDArray, path: Path) -> NDArray[np.float64]:
    cloud = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    if cloud.shape[0] == 0:
        raise CloudFormatError(f"{path}: the cloud has no points")
    finite = np.isfinite(cloud).all(axis=1)
    if not finite.all():
        bad = int(np.count_nonzero(~finite))
        raise CloudFormatError(
            f"{path}: {bad} of {cloud.shape[0]} points have NaN or inf coordinates (first at "
            f"index {int(np.flatnonzero(~finite)[0])}); remove them (e.g. the invalid pixels of "
            "an organised depth cloud) before planning"
        )
    return cloud


# ----------------------------------------------------------------------------- PLY
def _read_header(data: bytes, end_token: bytes, path: Path, kind: str) -> tuple[list[str], int]:
    """Header lines (decoded) and the byte offset where the body starts."""
    match = re.search(rb"^" + re.escape(end_token) + rb"[^\n]*\n", data, flags=re.MULTILINE)
    if match is None:
        raise CloudFormatError(f"{path}: not a {kind} file (no '{end_token.decode()}' line)")
    try:
        text = data[: match.start()].decode("ascii")
    except UnicodeDecodeError:
        raise CloudFormatError(f"{path}: the {kind} header is not ASCII text") from None
    return [line.strip() for line in text.splitlines()], match.end()


def _read_ply(path: Path) -> NDArray:
    data = path.read_bytes()
    if not data.startswith(b"ply"):
        raise CloudFormatError(f"{path}: not a PLY file (it must start with 'ply')")
    lines, body = _read_header(data, b"end_header", path, "PLY")
    fmt, elements = _ply_header(path, lines[1:])
    vertex = next((i for i, e in enumerate(elements) if e["name"] == "vertex"), None)
    if vertex is None:
        raise CloudFormatError(f"{path}: the PLY file has no 'vertex' element")
    props = elements[vertex]["props"]
    names = [name for name, _ in props]
    missing = [axis for axis in "xyz" if axis not in names]
    if missing:
        raise CloudFormatError(f"{path}: the PLY vertices lack the properties {missing}")
    if any(t is None for _, t in props):
        raise CloudFormatError(f"{path}: PLY vertices with list properties are not supported")
    if fmt == "ascii":
        return _ply_ascii(path, data[body:], elements, vertex)
    return _ply_binary(
        path, data, body, elements, vertex, "<" if fmt == "binary_little_endian" else ">"
    )


def _ply_header(path: Path, lines: list[str]) -> tuple[str, list[dict]]:
    """The PLY format and its elements in file order, each ``{"name", "count", "props"}`` with
    props ``(name, numpy type)`` (type None: a list property)."""
    fmt = None
    elements: list[dict] = []
    for line in lines:
        words = line.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format" and len(words) >= 2:
            fmt = words[1]
        elif words[0] == "element" and len(words) == 3:
            elements.append({"name": words[1], "count": int(words[2]), "props": []})
        elif words[0] == "property" and elements:
            if words[1] == "list":
                elements[-1]["props"].append((words[-1], None))
            elif len(words) == 3 and words[1] in _PLY_TYPES:
                elements[-1]["props"].append((words[2], _PLY_TYPES[words[1]]))
            else:
                raise CloudFormatError(f"{path}: unknown PLY property line {line!r}")
        else:
            raise CloudFormatError(f"{path}: unexpected PLY header line {line!r}")
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise CloudFormatError(f"{path}: unsupported PLY format {fmt!r}")
    return fmt, elements


def _ply_ascii(path: Path, body: bytes, elements: list[dict], vertex: int) -> NDArray:
    props, count = elements[vertex]["props"], elements[vertex]["count"]
    names = [name for name, _ in props]
    rows = body.decode("ascii", errors="replace").splitlines()
    start = sum(e["count"] for e in elements[:vertex])
    block = rows[start : start + count]
    if len(block) < count:
        raise CloudFormatError(
            f"{path}: the PLY file promises {count} vertices but has {len(block)}"
        )
    try:
        values = np.array([row.split()[: len(props)] for row in block], dtype=np.float64)
    except ValueError as exc:
        raise CloudFormatError(f"{path}: bad PLY vertex line: {exc}") from None
    values = values.reshape(-1, len(props)) if count == 0 else values
    if values.shape != (count, len(props)):
        raise CloudFormatError(f"{path}: PLY vertex lines must have {len(props)} values")
    return values[:, [names.index(axis) for axis in "xyz"]]


def _ply_binary(
    path: Path, data: bytes, body: int, elements: list[dict], vertex: int, order: str
) -> NDArray:
    offset = body
    for element in elements[:vertex]:
        if any(t is None for _, t in element["props"]):
            raise CloudFormatError(
                f"{path}: element {element['name']!r} with list properties comes before the "
                "vertices; only elements after the vertices may have lists"
            )
        offset += (
            element["count"] * np.dtype([(n, order + t) for n, t in element["props"]]).itemsize
        )
    count = elements[vertex]["count"]
    dtype = np.dtype([(n, order + t) for n, t in elements[vertex]["props"]])
    if len(data) < offset + count * dtype.itemsize:
        raise CloudFormatError(
            f"{path}: the PLY file is truncated ({count} vertices of {dtype.itemsize} bytes "
            "promised)"
        )
    rec = np.frombuffer(data, dtype=dtype, count=count, offset=offset)
    return np.column_stack([rec[axis].astype(np.float64) for axis in "xyz"])


# ----------------------------------------------------------------------------- PCD
def _read_pcd(path: Path) -> NDArray:
    data = path.read_bytes()
    fields, mode, start = _pcd_header(path, data)
    names, counts, total = _pcd_layout(path, fields)
    if mode == "ascii":
        return _pcd_ascii(path, data[start:], names, counts, total)
    if mode == "binary":
        return _pcd_binary(path, data, start, fields, names, counts, total)
    raise CloudFormatError(
        f"{path}: PCD 'DATA {mode}' is not supported; save it as 'ascii' or 'binary' "
        "(e.g. Open3D: o3d.io.write_point_cloud(path, pcd, compressed=False))"
    )


def _pcd_header(path: Path, data: bytes) -> tuple[dict[str, list[str]], str, int]:
    """The PCD header's lines by keyword (``FIELDS`` -> its words), the ``DATA`` mode and the
    offset where the points start."""
    match = re.search(rb"^DATA[ \t]+(\S+)[^\n]*\n", data, flags=re.MULTILINE)
    if match is None:
        raise CloudFormatError(f"{path}: not a PCD file (no 'DATA' line)")
    try:
        header = data[: match.start()].decode("ascii")
    except UnicodeDecodeError:
        raise CloudFormatError(f"{path}: the PCD header is not ASCII text") from None
    fields: dict[str, list[str]] = {}
    for line in header.splitlines():
        words = line.split()
        if words and not words[0].startswith("#"):
            fields[words[0].upper()] = words[1:]
    return fields, match.group(1).decode("ascii", errors="replace"), match.end()


def _pcd_layout(path: Path, fields: dict[str, list[str]]) -> tuple[list[str], list[int], int]:
    """The field names (x, y and z among them), each field's value count, and the point count."""
    names = fields.get("FIELDS")
    if not names:
        raise CloudFormatError(f"{path}: the PCD header has no FIELDS line")
    missing = [axis for axis in "xyz" if axis not in names]
    if missing:
        raise CloudFormatError(f"{path}: the PCD fields {names} lack {missing}")
    counts = [int(c) for c in fields.get("COUNT", ["1"] * len(names))]
    try:
        points_line = fields.get("POINTS")
        if points_line:
            total = int(points_line[0])
        else:
            total = int(fields["WIDTH"][0]) * int(fields.get("HEIGHT", ["1"])[0])
    except (KeyError, ValueError, IndexError):
        raise CloudFormatError(f"{path}: the PCD header gives no point count") from None
    return names, counts, total


def _pcd_ascii(path: Path, body: bytes, names: list[str], counts: list[int], total: int) -> NDArray:
    columns = np.cumsum([0, *counts])
    rows = body.decode("ascii", errors="replace").split("\n")
    rows = [r for r in rows if r.strip()][:total]
    try:
        values = np.array([r.split() for r in rows], dtype=np.float64)
    except ValueError as exc:
        raise CloudFormatError(f"{path}: bad PCD data line: {exc}") from None
    if values.ndim != 2 or values.shape != (total, int(columns[-1])):
        raise CloudFormatError(
            f"{path}: the PCD header promises {total} points of {int(columns[-1])} values"
        )
    index = {name: int(columns[i]) for i, name in enumerate(names)}
    return values[:, [index[axis] for axis in "xyz"]]


def _pcd_binary(
    path: Path,
    data: bytes,
    start: int,
    fields: dict[str, list[str]],
    names: list[str],
    counts: list[int],
    total: int,
) -> NDArray:
    sizes = [int(s) for s in fields.get("SIZE", [])]
    types = fields.get("TYPE", [])
    if len(sizes) != len(names) or len(types) != len(names):
        raise CloudFormatError(f"{path}: the PCD header needs SIZE and TYPE for each field")
    try:
        dtype = np.dtype(
            [
                (name, "<" + _PCD_TYPES[(t.upper(), s)], (c,))
                for name, s, t, c in zip(names, sizes, types, counts, strict=True)
            ]
        )
    except KeyError as exc:
        raise CloudFormatError(f"{path}: unsupported PCD field type {exc}") from None
    if len(data) < start + total * dtype.itemsize:
        raise CloudFormatError(f"{path}: the PCD file is truncated ({total} points promised)")
    rec = np.frombuffer(data, dtype=dtype, count=total, offset=start)
    return np.column_stack([rec[axis][:, 0].astype(np.float64) for axis in "xyz"])


# ----------------------------------------------------------------------------- NPY, XYZ
def _read_npy(path: Path) -> NDArray:
    try:
        arr = np.load(path, allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise CloudFormatError(f"{path}: not a readable .npy array: {exc}") from None
    if arr.dtype.names:
        missing = [axis for axis in "xyz" if axis not in arr.dtype.names]
        if missing:
            raise CloudFormatError(f"{path}: the structured array lacks fields {missing}")
        return np.column_stack([arr[axis].astype(np.float64).ravel() for axis in "xyz"])
    if arr.ndim != 2 or arr.shape[1] != 3 or not np.issubdtype(arr.dtype, np.number):
        raise CloudFormatError(
            f"{path}: expected an (N, 3) numeric array, got shape {arr.shape} of {arr.dtype}"
        )
    return arr


def _read_xyz(path: Path) -> NDArray:
    try:
        text = path.read_text()
    except UnicodeDecodeError:
        raise CloudFormatError(f"{path}: an .xyz file must be text") from None
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        words = re.split(r"[\s,;]+", line)
        if len(words) < 3:
            raise CloudFormatError(f"{path}:{number}: expected at least 3 numbers, got {line!r}")
        rows.append(words[:3])
    if not rows:
        return np.zeros((0, 3))
    try:
        return np.array(rows, dtype=np.float64)
    except ValueError as exc:
        raise CloudFormatError(f"{path}: not a number in an .xyz line: {exc}") from None


_READERS = {".ply": _read_ply, ".pcd": _read_pcd, ".npy": _read_npy, ".xyz": _read_xyz}


def read_cloud(path: str | Path) -> NDArray[np.float64]:
    """Read a point cloud file into an (N, 3) float64 array (metres, as stored).

    Raises:
        FileNotFoundError: the file does not exist.
        CloudFormatError: unknown suffix, unparsable content, no points, or NaN/inf points.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in _READERS:
        raise CloudFormatError(
            f"{path}: unknown cloud format {suffix or '(no suffix)'!r}; use one of "
            f"{', '.join(CLOUD_SUFFIXES)}"
        )
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    try:
        points = _READERS[suffix](path)
    except (IndexError, KeyError, TypeError, ValueError) as exc:
        if isinstance(exc, CloudFormatError):
            raise
        raise CloudFormatError(f"{path}: cannot parse the {suffix} file: {exc}") from None
    return _finish(points, path)


def write_cloud(path: str | Path, points: ArrayLike, *, binary: bool = True) -> Path:
    """Write an (N, 3) cloud as ``.ply``, ``.pcd`` (binary or ascii), ``.npy`` or ``.xyz``.

    Binary PLY and PCD store float64 little-endian, so a round trip is exact.
    """
    path = Path(path)
    cloud = np.asarray(points, dtype=np.float64)
    if cloud.ndim != 2 or cloud.shape[1] != 3:
        raise ValueError(f"points must have shape (N, 3), got {cloud.shape}")
    suffix = path.suffix.lower()
    n = cloud.shape[0]
    if suffix == ".npy":
        np.save(path, cloud)
    elif suffix == ".xyz":
        np.savetxt(path, cloud, fmt="%.9g")
    elif suffix == ".ply":
        fmt = "binary_little_endian" if binary else "ascii"
        header = (
            f"ply\nformat {fmt} 1.0\nelement vertex {n}\n"
            "property double x\nproperty double y\nproperty double z\nend_header\n"
        )
        with path.open("wb") as f:
            f.write(header.encode("ascii"))
            if binary:
                f.write(cloud.astype("<f8").tobytes())
            else:
                np.savetxt(f, cloud, fmt="%.17g")
    elif suffix == ".pcd":
        mode = "binary" if binary else "ascii"
        header = (
            "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\n"
            f"SIZE 8 8 8\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n"
            f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {mode}\n"
        )
        with path.open("wb") as f:
            f.write(header.encode("ascii"))
            if binary:
                f.write(cloud.astype("<f8").tobytes())
            else:
                np.savetxt(f, cloud, fmt="%.17g")
    else:
        raise ValueError(f"{path}: cannot write {suffix!r}; use one of {', '.join(CLOUD_SUFFIXES)}")
    return path
