"""The Siconos .dat reader refuses malformed files, naming the file and the position, and never allocates
what a header claims before checking it."""
import os
import tracemalloc

import numpy as np
import pytest

from converters.errors import LCPError, ResourceError
from converters.lcp import read_siconos_lcp

DENSE_2 = "2\n0\n2 2\n2 2\n2 1\n1 2\n-5 -6\n"          # M = [[2, 1], [1, 2]] column-major, q = (-5, -6)
# ortiz_block's layout: 2 x 2 blocks of 2 x 2, all four present
BLOCK_4 = ("4\n1\n4 4\n4\n2 2\n2 4\n2 4\n3\n4\n0 2 4\n0 1 0 1\n"
           "0\n3 -1 1 2\n1\n0 1 -1 1\n2\n0 0 1 0\n3\n3 1 -1 2\n-2 1 -1 1\n")


@pytest.fixture(autouse=True)
def memory_limit(monkeypatch):
    monkeypatch.setenv("PCSUITE_MAX_MEMORY", "1G")


def write(tmp_path, text, name="lcp_t.dat"):
    path = tmp_path / name
    path.write_bytes(text.encode() if isinstance(text, str) else text)
    return path


def test_the_reference_layouts_read_correctly(tmp_path, peer):
    p = read_siconos_lcp(write(tmp_path, DENSE_2 + "free text: nan inf 1e999 abc\n"))
    np.testing.assert_array_equal(p.M, [[2.0, 1.0], [1.0, 2.0]])
    np.testing.assert_array_equal(p.q, [-5.0, -6.0])
    assert p.name == "t" and p.comment == "free text: nan inf 1e999 abc"   # after q: free text, never parsed
    block = read_siconos_lcp(write(tmp_path, BLOCK_4, "b.dat"))
    np.testing.assert_array_equal(block.M, read_siconos_lcp(peer / "lcp_ortiz_block.dat").M)
    fortran = read_siconos_lcp(write(tmp_path, "1 0 1 1 1 1 2.5D+00 -1.0d-1", "f.dat"))
    assert fortran.M[0, 0] == 2.5 and fortran.q[0] == -0.1


@pytest.mark.parametrize("text,message", [
    ("-2\n0\n2 2\n2 2\n", r"n must be >= 1; got -2 \(token 1, line 1\)"),
    ("0\n0\n0 0\n0 0\n", r"n must be >= 1; got 0 \(token 1, line 1\)"),
    ("2.5\n0\n2 2\n", r"token '2\.5' at position 1 \(line 1\) is not an integer \(reading n\)"),
    ("2\n0\n2 2.0\n", r"token '2\.0' at position 4 \(line 3\) is not an integer \(reading size1\)"),
    ("2\n3\n2 2\n", r"storage type must be 0 \(dense\) or 1 \(sparse-block\); got 3 \(token 2, line 2\)"),
    ("2\n-1\n2 2\n", r"storage type must be 0 \(dense\) or 1 \(sparse-block\); got -1 \(token 2, line 2\)"),
    ("2\n0\n2 3\n", r"sizes must agree with n \(size0 = size1 = n = 2\); got size0 = 2, size1 = 3 \(token 4, line 3\)"),
    ("2\n0\n2 2\n2 3\n1 0 0 1\n-1 -1\n",
     r"the dense header repeats size0 size1 = 2 2; got 2 3 \(token 6, line 4\)"),
    ("2\n0\n2 2\n2 2\n1 nan\n0 1\n-1 -1\n",
     r"token 'nan' at position 8 \(line 5\) is not a finite number \(reading M\)"),
    ("2\n0\n2 2\n2 2\n1 0\n0 1\n-1 inf\n",
     r"token 'inf' at position 12 \(line 7\) is not a finite number \(reading q\)"),
    ("2\n0\n2 2\n2 2\n1 0\n0 1e400\n-1 -1\n",
     r"token '1e400' at position 10 \(line 6\) is not a finite number \(reading M\)"),
    ("2\n0\n2 2\n2 2\n1 0\nzero 1\n-1 -1\n",
     r"token 'zero' at position 9 \(line 6\) is not a finite number \(reading M\)"),
    ("2\n0\n2 2\n2 2\n1 0\n0 1\n-1\n", r"file ends while reading q \(after 11 tokens\)"),
    ("2\n0\n2 2\n2 2\n1 0\n0 1\n",
     r"file ends while reading q \(needs 2 numbers after token 10; only 1 characters"),
    ("2\n0\n2 2\n2 2\n1 0\n0 1\n-1 x\n", r"token 'x' at position 12 \(line 7\) is not a finite number \(reading q\)"),
    ("", r"file ends while reading n \(after 0 tokens\)"),
])
def test_malformed_dense_files_are_refused_naming_file_and_position(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(LCPError, match="^" + str(path).replace(".", r"\.") + ": " + message):
        read_siconos_lcp(path)


def _block(tokens):
    """BLOCK_4's tokens, its lines kept (the messages name lines too)."""
    lines, out, i = BLOCK_4.splitlines(), [], 0
    for line in lines:
        count = len(line.split())
        out.append(" ".join(tokens[i:i + count]))
        i += count
    return "\n".join(out) + "\n"


@pytest.mark.parametrize("edit,message", [
    # (token index in BLOCK_4 counted from 1, new value), expected message
    ((8, -2), r"cumulative row block size 0 must be in \[1, 3\] \(strictly increasing\); got -2 \(token 8, line 6\)"),
    ((8, 4), r"cumulative row block size 0 must be in \[1, 3\] \(strictly increasing\); got 4 \(token 8,"),
    ((9, 2), r"cumulative row block size 1 must be = 4 \(strictly increasing, the last = n = 4\); got 2 \(token 9,"),
    ((11, 5), r"cumulative column block size 1 must be = 4 \(strictly increasing, the last = n = 4\); got 5 "
              r"\(token 11, line 7\)"),
    ((6, 5), r"blocknumber0 must be in \[1, 4\]; got 5 \(token 6, line 5\)"),
    ((6, 0), r"blocknumber0 must be in \[1, 4\]; got 0 \(token 6,"),
    ((12, 4), r"filled1 must be = 3 \(blocknumber0 \+ 1 block-row pointers\); got 4 \(token 12, line 8\)"),
    ((13, 5), r"filled2 must be = 4 \(one block-column index per block, nbblocks\); got 5 \(token 13,"),
    ((14, 1), r"block-row pointer 0 must be = 0; got 1 \(token 14, line 10\)"),
    ((15, 3), r"block-row pointer 1 must be in \[0, 2\] \(non-decreasing by at most blocknumber1 = 2, <= "
              r"nbblocks\); got 3 \(token 15,"),
    ((15, -1), r"block-row pointer 1 must be in \[0, 2\] .*; got -1 \(token 15,"),
    ((15, 0), r"block-row pointers leave 4 blocks to the last block row, more than blocknumber1 = 2 \(token 16,"),
    ((16, 3), r"block-row pointer 2 must be = 4 \(the last = nbblocks = 4, .*\); got 3 \(token 16,"),
    ((18, 0), r"block-column index of block 1 must be = 1 \(increasing within a block row, below "
              r"blocknumber1\); got 0 \(token 18, line 11\)"),
    ((18, 2), r"block-column index of block 1 must be = 1 .*; got 2 \(token 18,"),
    ((19, -1), r"block-column index of block 2 must be in \[0, 1\] .*; got -1 \(token 19,"),
    ((21, 1), r"block number must be = 0 \(blocks numbered in order\); got 1 \(token 21, line 12\)"),
    ((26, 0), r"block number must be = 1 \(blocks numbered in order\); got 0 \(token 26,"),
    ((5, -1), r"nbblocks must be in \[0, 16\]; got -1 \(token 5, line 4\)"),
    ((5, 17), r"nbblocks must be in \[0, 16\]; got 17 \(token 5,"),
    ((5, 5), r"nbblocks = 5 must be <= blocknumber0 x blocknumber1 = 4 \(token 7,"),
    ((23, "nan"), r"token 'nan' at position 23 \(line 13\) is not a finite number \(reading block 0\)"),
    ((7, 2.0), r"token '2\.0' at position 7 \(line 5\) is not an integer \(reading blocknumber1\)"),
])
def test_malformed_sparse_block_files_are_refused(tmp_path, edit, message):
    tokens = BLOCK_4.split()
    index, value = edit
    tokens[index - 1] = str(value)
    path = write(tmp_path, _block(tokens))
    with pytest.raises(LCPError, match="^" + str(path).replace(".", r"\.") + ": " + message):
        read_siconos_lcp(path)


def test_a_negative_block_size_no_longer_moves_the_reader_backwards(tmp_path):
    # deudeu_block with its row block size -2: the old reader read garbage and the problem was "solved"
    text = "2\n1\n2 2\n1\n1 1\n-2\n2\n2 1\n0 1\n0\n0\n2 1 1 2\n-5 -6\n"
    path = write(tmp_path, text)
    with pytest.raises(LCPError, match=r"cumulative row block size 0 must be = 2 .*; got -2 \(token 8, line 6\)"):
        read_siconos_lcp(path)


def test_no_blocks_is_a_zero_matrix(tmp_path):
    p = read_siconos_lcp(write(tmp_path, "3 1 3 3 0 1 2 3"))
    np.testing.assert_array_equal(p.M, np.zeros((3, 3)))
    np.testing.assert_array_equal(p.q, [1.0, 2.0, 3.0])


@pytest.mark.parametrize("data,byte,offset", [
    (b"2\n0\n\xff\xfe2 2\n", 0xFF, 4),
    (b"\x7fELF\x02\x01\x01\x00", 0x7F, 0),
    (b"2\n0\n2 2\x00\x00", 0x00, 7),
])
def test_a_binary_file_is_refused_with_its_name_and_the_byte(tmp_path, data, byte, offset):
    path = write(tmp_path, data)
    with pytest.raises(LCPError, match=f"^{str(path)}".replace(".", r"\.")
                       + rf" is not a text \.dat file \(byte 0x{byte:02x} at offset {offset}\)$"):
        read_siconos_lcp(path)


@pytest.mark.parametrize("path,kind", [("/dev/zero", "a character device"), ("/tmp", "a directory")])
def test_non_regular_files_are_refused_at_once(path, kind):
    if not os.path.exists(path):
        pytest.skip(f"{path} does not exist here")
    tracemalloc.start()
    try:
        with pytest.raises(LCPError, match=f"^FILE must be a regular file; got '{path}', {kind}$"):
            read_siconos_lcp(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 << 10                 # refused by its kind: nothing read (/dev/zero never ends)


def test_a_pipe_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "pipe.dat"
    os.mkfifo(fifo)
    with pytest.raises(LCPError, match=r"FILE must be a regular file; got '.*pipe\.dat', a pipe$"):
        read_siconos_lcp(fifo)


def test_a_missing_file_is_refused(tmp_path):
    with pytest.raises(LCPError, match=r"^FILE must be a readable Siconos \.dat LCP file; got '.*nope\.dat' "
                                       r"\(No such file or directory\)$"):
        read_siconos_lcp(tmp_path / "nope.dat")


@pytest.mark.parametrize("n,needed", [(10**6, r"7\.28 TiB"), (50_000, r"18\.6 GiB"), (11_600, r"1 GiB")])
def test_a_header_too_large_for_memory_is_refused_before_allocating(tmp_path, n, needed):
    path = write(tmp_path, f"{n}\n0\n{n} {n}\n{n} {n}\n1 2 3\n")
    tracemalloc.start()
    try:
        with pytest.raises(ResourceError, match=rf"^reading {str(path)}: n = {n} \(dense M of n\^2 doubles\) needs "
                                                rf"about {needed}, above the memory limit of 1 GiB; use a smaller LCP"
                                                r".*--max-memory"):
            read_siconos_lcp(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1 << 20                          # refused from the header: nothing near 8 n^2 bytes allocated


def test_a_header_within_the_limit_but_a_short_file_ends_before_allocating_M(tmp_path):
    path = write(tmp_path, "10000\n0\n10000 10000\n10000 10000\n1 2 3\n")   # M would be 800 MB: under 1 GiB
    tracemalloc.start()
    try:
        with pytest.raises(LCPError, match=r"file ends while reading M \(needs 100000000 numbers after token 6; "
                                           r"only 7 characters remain\)"):
            read_siconos_lcp(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1 << 20


def test_a_file_larger_than_the_memory_limit_is_refused_unread(tmp_path, monkeypatch):
    monkeypatch.setenv("PCSUITE_MAX_MEMORY", "16M")
    path = tmp_path / "lcp_huge.dat"
    with open(path, "wb") as handle:                 # a sparse 20 MB file: nothing is written but its size
        handle.write(DENSE_2.encode())
        handle.truncate(20 * 10**6)
    with pytest.raises(ResourceError, match=rf"^reading {str(path)} \(20000000 bytes of text, held twice while "
                                            r"decoded\) needs about 38\.1 MiB, above the memory limit of 16 MiB"):
        read_siconos_lcp(path)
