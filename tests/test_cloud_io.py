"""Cloud files: every format round-trips, hand-written files parse, bad files are refused."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from hsqbench.cloud_io import CloudFormatError, read_cloud, write_cloud

POINTS = np.array([[0.1, -0.2, 0.3], [1.5e-3, 2.0, -7.25], [0.0, 0.0, 1.0], [4.0, 5.0, 6.0]])


@pytest.mark.parametrize("suffix", [".ply", ".pcd", ".npy", ".xyz"])
@pytest.mark.parametrize("binary", [True, False])
def test_round_trip(tmp_path, suffix, binary) -> None:
    path = write_cloud(tmp_path / f"cloud{suffix}", POINTS, binary=binary)
    np.testing.assert_allclose(read_cloud(path), POINTS, rtol=1e-9)


def test_ascii_ply_with_extra_properties_and_faces(tmp_path) -> None:
    text = """ply
format ascii 1.0
comment made by hand
element vertex 3
property float y
property float x
property uchar red
property float z
property float nx
element face 1
property list uchar int vertex_indices
end_header
2 1 255 3 0.5
5 4 0 6 0.5
8 7 10 9 0.5
3 0 1 2
"""
    path = tmp_path / "hand.ply"
    path.write_text(text)
    np.testing.assert_allclose(read_cloud(path), [[1, 2, 3], [4, 5, 6], [7, 8, 9]])


@pytest.mark.parametrize("order", ["<", ">"])
def test_binary_ply_with_float32_and_a_leading_element(tmp_path, order) -> None:
    fmt = "binary_little_endian" if order == "<" else "binary_big_endian"
    header = (
        f"ply\nformat {fmt} 1.0\nelement camera 1\nproperty double focal\n"
        "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
        "property uchar alpha\nelement face 0\nproperty list uchar int vertex_indices\n"
        "end_header\n"
    )
    body = struct.pack(order + "d", 500.0)
    body += struct.pack(order + "fffB", 1.0, 2.0, 3.0, 7) + struct.pack(
        order + "fffB", -1, -2, -3, 9
    )
    path = tmp_path / "bin.ply"
    path.write_bytes(header.encode() + body)
    np.testing.assert_allclose(read_cloud(path), [[1, 2, 3], [-1, -2, -3]])


def test_pcd_with_extra_fields_ascii_and_binary(tmp_path) -> None:
    header = (
        "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\n"
        "COUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\n"
    )
    ascii_path = tmp_path / "a.pcd"
    ascii_path.write_text(header + "DATA ascii\n1 2 3 4278190080\n4 5 6 0\n")
    np.testing.assert_allclose(read_cloud(ascii_path), [[1, 2, 3], [4, 5, 6]])
    binary_path = tmp_path / "b.pcd"
    body = struct.pack("<fffI", 1, 2, 3, 5) + struct.pack("<fffI", 4, 5, 6, 6)
    binary_path.write_bytes((header + "DATA binary\n").encode() + body)
    np.testing.assert_allclose(read_cloud(binary_path), [[1, 2, 3], [4, 5, 6]])


def test_xyz_with_commas_comments_and_extra_columns(tmp_path) -> None:
    path = tmp_path / "c.xyz"
    path.write_text("# x y z nx ny nz\n1,2,3,0,0,1\n\n4 5 6 0 0 1  # trailing\n")
    np.testing.assert_allclose(read_cloud(path), [[1, 2, 3], [4, 5, 6]])


def test_structured_npy(tmp_path) -> None:
    arr = np.zeros(2, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("i", "u1")])
    arr["x"], arr["y"], arr["z"] = [1, 4], [2, 5], [3, 6]
    np.save(tmp_path / "s.npy", arr)
    np.testing.assert_allclose(read_cloud(tmp_path / "s.npy"), [[1, 2, 3], [4, 5, 6]])


BAD_FILES = {
    "empty.ply": (b"", "not a PLY"),
    "novertex.ply": (b"ply\nformat ascii 1.0\nelement face 0\nend_header\n", "no 'vertex'"),
    "zero.ply": (
        b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
        b"property float z\nend_header\n",
        "no points",
    ),
    "short.ply": (
        b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\n"
        b"property float y\nproperty float z\nend_header\n" + b"\x00" * 20,
        "truncated",
    ),
    "noz.ply": (
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
        b"end_header\n1 2\n",
        "lack",
    ),
    "nan.xyz": (b"1 2 3\nnan 0 0\n", "NaN or inf"),
    "words.xyz": (b"1 2 three\n", "not a number"),
    "two.xyz": (b"1 2\n", "at least 3"),
    "blank.xyz": (b"# nothing\n", "no points"),
    "compressed.pcd": (
        b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\n"
        b"POINTS 1\nDATA binary_compressed\n\x00\x00",
        "binary_compressed",
    ),
    "inf.pcd": (
        b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\n"
        b"POINTS 1\nDATA ascii\ninf 0 0\n",
        "NaN or inf",
    ),
    "garbage.npy": (b"not numpy at all", "not a readable"),
    "cloud.obj": (b"v 1 2 3\n", "unknown cloud format"),
}


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_bad_files_are_refused_with_a_reason(tmp_path, name) -> None:
    content, needle = BAD_FILES[name]
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(CloudFormatError, match=needle):
        read_cloud(path)


def test_wrong_npy_shape_and_missing_file(tmp_path) -> None:
    np.save(tmp_path / "flat.npy", np.zeros((4, 2)))
    with pytest.raises(CloudFormatError, match=r"\(N, 3\)"):
        read_cloud(tmp_path / "flat.npy")
    with pytest.raises(FileNotFoundError):
        read_cloud(tmp_path / "missing.ply")
