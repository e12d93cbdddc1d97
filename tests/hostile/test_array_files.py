"""Hostile depth and prior files: headers that lie, cut-short and mutated files, huge
declared sizes (issue 13, items 15 and 17). Every outcome is a ValueError naming the file,
decided before anything large is allocated, or a correct read."""
import struct
import zlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from monitor.depth.files import load_depth, save_depth_png
from monitor.depth.prior import check_prior, load_prior, save_prior
from monitor.userfiles import MAX_PIXELS, check_png_size, read_npy, write_npy


def _npy_bytes(array):
    import io
    buffer = io.BytesIO()
    np.save(buffer, array, allow_pickle=False)
    return buffer.getvalue()


def _npy_header(shape, descr="<f4", total=128):
    """A version 1.0 .npy header declaring ``shape`` (no data after it)."""
    text = f"{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape!r}, }}"
    text += " " * (total - 10 - len(text) - 1) + "\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(text)) + text.encode("latin1")


def test_empty_npy_is_an_error_naming_the_file(tmp_path):
    path = tmp_path / "empty.npy"
    path.write_bytes(b"")
    for load in (load_depth, load_prior):
        with pytest.raises(ValueError, match=r"empty.npy: not a .npy file \(0 bytes"):
            load(path)


def test_huge_declared_shape_is_refused_before_allocating(tmp_path):
    # 192 bytes declaring 30000 x 30000 float32 (3.6 GB): the file holds 64 bytes of data
    path = tmp_path / "huge.npy"
    path.write_bytes(_npy_header((30000, 30000)) + bytes(64))
    assert path.stat().st_size == 192
    with pytest.raises(ValueError, match=r"huge.npy: the header declares shape \(30000, 30000\) of float32 "
                                         r"\(3600000000 bytes of data\) but the file holds 64 bytes"):
        load_depth(path)
    with pytest.raises(ValueError, match="prior file .*huge.npy"):
        load_prior(path)


def test_pixel_limit_for_a_consistent_file(tmp_path):
    # a real file of 60 million uint8 elements (60 MB) is over the 50 M limit whatever its dtype
    path = tmp_path / "big.npy"
    path.write_bytes(_npy_header((6000, 10000), "|u1") + bytes(60_000_000))
    with pytest.raises(ValueError, match=f"big.npy: shape \\(6000, 10000\\) has 60000000 elements, more than "
                                         f"the limit of {MAX_PIXELS}"):
        read_npy(path)
    assert read_npy(path, max_elements=60_000_000).shape == (6000, 10000)


def test_png_declaring_20000_squared_pixels_is_refused_from_its_header(tmp_path):
    # a valid PNG header (IHDR) of a 20000 x 20000 16-bit grey image, and no image data
    ihdr = struct.pack(">IIBBBBB", 20000, 20000, 16, 0, 0, 0, 0)
    chunk = struct.pack(">I", len(ihdr)) + b"IHDR" + ihdr + struct.pack(">I", zlib.crc32(b"IHDR" + ihdr))
    path = tmp_path / "huge.png"
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk)
    with pytest.raises(ValueError, match=r"huge.png: the header declares 20000 x 20000 = 400000000 pixels"):
        load_depth(path)


def test_good_files_still_read(tmp_path):
    depth = np.arange(1, 13, dtype=np.float32).reshape(3, 4)
    np.save(tmp_path / "d.npy", depth)
    np.testing.assert_array_equal(load_depth(tmp_path / "d.npy"), depth)
    np.save(tmp_path / "f.npy", np.asfortranarray(depth.astype(np.float64)))  # Fortran order, float64
    np.testing.assert_array_equal(load_depth(tmp_path / "f.npy"), depth)
    save_depth_png(tmp_path / "d.png", depth)
    np.testing.assert_array_equal(load_depth(tmp_path / "d.png"), depth)
    assert check_png_size(tmp_path / "d.png") == (3, 4)


@pytest.mark.parametrize("cut", [1, 6, 9, 10, 50, 127, 128, 129, 175])
def test_cut_short_npy_names_the_file(tmp_path, cut):
    data = _npy_bytes(np.ones((4, 12), np.float32))  # 128 header + 192 data bytes
    path = tmp_path / "cut.npy"
    path.write_bytes(data[:cut])
    with pytest.raises(ValueError, match="cut.npy"):
        load_depth(path)


def test_extra_bytes_after_the_data_are_refused(tmp_path):
    path = tmp_path / "long.npy"
    path.write_bytes(_npy_bytes(np.ones((2, 2), np.float32)) + b"junk")
    with pytest.raises(ValueError, match="long.npy: .* followed by extra bytes"):
        load_depth(path)


@settings(max_examples=60)
@given(flips=st.lists(st.tuples(st.integers(0, 159), st.integers(0, 255)), min_size=1, max_size=4),
       cut=st.integers(0, 160))
def test_mutated_npy_reads_correctly_or_is_a_named_error(tmp_path_factory, flips, cut):
    depth = np.linspace(1.0, 30.0, 8, dtype=np.float32).reshape(2, 4)
    data = bytearray(_npy_bytes(depth))  # 128 header + 32 data bytes
    for position, value in flips:
        data[position] = value
    data = bytes(data[:len(data) - cut])
    path = tmp_path_factory.mktemp("m") / "mutated.npy"
    path.write_bytes(data)
    try:
        result = load_depth(path)
    except ValueError as exc:
        assert "mutated.npy" in str(exc)
        return
    # read: a 2-D float32 map of the stored values, whose data is exactly the rest of the file
    raw = read_npy(path)
    assert result.dtype == np.float32 and result.ndim == 2 == raw.ndim
    assert raw.nbytes <= len(data) - 10  # magic, version and header length come first
    np.testing.assert_array_equal(result, raw.astype(np.float32))


@settings(max_examples=40)
@given(flips=st.lists(st.tuples(st.integers(0, 200), st.integers(0, 255)), min_size=1, max_size=4),
       cut=st.integers(0, 60))
def test_mutated_png_reads_or_is_a_named_error(tmp_path_factory, flips, cut):
    folder = tmp_path_factory.mktemp("p")
    save_depth_png(folder / "good.png", np.linspace(1.0, 30.0, 48, dtype=np.float32).reshape(6, 8))
    data = bytearray((folder / "good.png").read_bytes())
    for position, value in flips:
        if position < len(data):
            data[position] = value
    path = folder / "mutated.png"
    path.write_bytes(bytes(data[:max(len(data) - cut, 0)]))
    try:
        result = load_depth(path)
    except ValueError as exc:
        assert "mutated.png" in str(exc)
        return
    assert result.dtype == np.float32 and result.ndim == 2 and result.size <= MAX_PIXELS


def test_object_and_archive_files_are_refused(tmp_path):
    np.save(tmp_path / "obj.npy", np.array([None, 1], dtype=object), allow_pickle=True)
    with pytest.raises(ValueError, match="obj.npy: dtype object holds Python objects"):
        load_prior(tmp_path / "obj.npy")
    np.savez(tmp_path / "a.npz", x=np.ones(2))
    (tmp_path / "a.npz").rename(tmp_path / "a.npy")
    with pytest.raises(ValueError, match=r"a.npy: holds an archive \(.npz\)"):
        load_prior(tmp_path / "a.npy")


def test_float64_prior_beyond_float32_is_refused(tmp_path):
    prior = np.full((2, 3), 0.05)
    prior[1, 2] = 1e300  # finite in float64, inf after the float32 cast
    with pytest.raises(ValueError, match=r"first at row, col \(1, 2\): 1e\+300, too large for float32"):
        check_prior(prior)
    np.save(tmp_path / "p.npy", prior)
    with pytest.raises(ValueError, match="prior file .*p.npy: 1 pixels are inf, negative or too large"):
        load_prior(tmp_path / "p.npy")
    prior[1, 2] = 3e38  # within float32's range: kept
    assert np.isfinite(check_prior(prior)).all()


def test_writes_are_atomic(tmp_path, monkeypatch):
    path = tmp_path / "prior.npy"
    save_prior(path, np.full((2, 2), 0.1, np.float32))
    before = path.read_bytes()

    def fail(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(np, "save", fail)
    with pytest.raises(OSError, match="disk full"):
        save_prior(path, np.full((2, 2), 0.2, np.float32))
    assert path.read_bytes() == before  # untouched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["prior.npy"]  # no temporary left
    monkeypatch.undo()
    write_npy(path, np.zeros(3))
    assert read_npy(path).tolist() == [0.0, 0.0, 0.0]
