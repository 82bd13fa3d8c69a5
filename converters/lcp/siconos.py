"""Reader for the Siconos numerics ``.dat`` LCP format (dense and sparse-block storage).

Layout: n, storage (0 dense, 1 sparse-block), size0 size1; dense: size0 size1 again and the matrix
column-major; sparse-block: block counts, cumulative row/column block sizes, block-row pointers,
block-column indices, then each block (its number and nr*nc numbers, column-major). Then q.
Anything after q is free text (kept as ``comment``).

The reader refuses, naming the file and the position (token number, counted from 1, and line), every
header that is not a valid LCP (sizes < 1 or contradictory, storage other than 0/1, block structures that
do not tile the n x n matrix) and every token that is not a finite number where one is needed. It checks
the memory the header asks for (:func:`converters.limits.check_memory`) before allocating it, reads only
regular files no larger than the memory limit, and converts tokens one at a time as it needs them.
"""
from __future__ import annotations

import math
import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import NoReturn

import numpy as np

from .. import limits
from ..errors import LCPError
from ..validate import quoted

#: Tokens are separated by ASCII white space only, and numbers are ASCII digits: a no-break or thin space inside a
#: number (1\u00a0000) would split it into two numbers, and other scripts' digits (\u0661, \uff11) must not be read.
_TOKEN = re.compile(r"[^ \t\n\r\f\v]+")
_FLOAT = re.compile(r"^[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eEdD][+-]?[0-9]+)?$")
_INT = re.compile(r"^[+-]?[0-9]+$")
#: The longest integer a header holds (n^2 doubles of a 19-digit n are beyond any memory limit anyway).
_INT_DIGITS = 18
_CONTROL = re.compile(r"[\x00-\x08\x0e-\x1f\x7f]")
_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISFIFO, "a pipe"), (stat.S_ISSOCK, "a socket"))


@dataclass(frozen=True)
class LCPFile:
    name: str
    M: np.ndarray
    q: np.ndarray
    comment: str


def read_siconos_lcp(path: str | os.PathLike[str], *, context: str = "reading") -> LCPFile:
    """Read a Siconos .dat LCP file. ``context`` starts the memory-limit message (the CLI passes ``lcp solve``)."""
    path = Path(path)
    text = _read_text(path)
    reader = _Tokens(text, quoted(path))
    n = reader.int("n", low=1)
    limits.check_memory(f"{context} {quoted(path)}: n = {n} (dense M of n^2 doubles)", 8.0 * n * n,
                        remedy="a smaller LCP")
    storage = reader.int("storage type")
    if storage not in (0, 1):
        reader.fail(f"storage type must be 0 (dense) or 1 (sparse-block); got {storage}")
    size0 = reader.int("size0")
    size1 = reader.int("size1")
    if size0 != n or size1 != n:
        reader.fail(f"sizes must agree with n (size0 = size1 = n = {n}); got size0 = {size0}, size1 = {size1}")
    if storage == 0:
        again = reader.int("size0 (repeated)"), reader.int("size1 (repeated)")
        if again != (size0, size1):
            reader.fail(f"the dense header repeats size0 size1 = {size0} {size1}; got {again[0]} {again[1]}")
        M = np.ascontiguousarray(reader.numbers(n * n, "M").reshape((n, n), order="F"))   # stored by columns
    else:
        M = _read_sparse_block(reader, n)
    q = reader.numbers(n, "q")
    comment = " ".join(text[reader.offset:].split())
    return LCPFile(name=path.stem.removeprefix("lcp_"), M=M, q=q, comment=comment)


def _read_text(path: Path) -> str:
    """The file's text: a regular file no larger than the memory limit, UTF-8 (ASCII) without control bytes."""
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode):
            kind = next((name for test, name in _KINDS if test(info.st_mode)), "not a regular file")
            raise LCPError(f"FILE must be a regular file; got {str(path)!r}, {kind}")
        # the bytes and the decoded text are both held; never read more than the size checked here
        limits.check_memory(f"reading {quoted(path)} ({info.st_size} bytes of text, held twice while decoded)",
                            2.0 * info.st_size, remedy="a smaller LCP")
        with open(path, "rb") as handle:
            data = handle.read(info.st_size + 1)
    except OSError as exc:
        raise LCPError(f"FILE must be a readable Siconos .dat LCP file; got {str(path)!r} "
                       f"({exc.strerror or exc})") from None
    if len(data) > info.st_size:  # grew after stat
        raise LCPError(f"FILE must not change while it is read; {str(path)!r} grew beyond its size of "
                       f"{info.st_size} bytes")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise LCPError(f"{quoted(path)} is not a text .dat file (byte 0x{data[exc.start]:02x} at offset {exc.start})") from None
    bad = _CONTROL.search(text)
    if bad:
        offset = len(text[:bad.start()].encode("utf-8"))
        raise LCPError(f"{quoted(path)} is not a text .dat file (byte 0x{ord(bad.group()):02x} at offset {offset})")
    return text


def _read_sparse_block(reader: "_Tokens", n: int) -> np.ndarray:
    """The n x n matrix of a sparse-block (CSR of blocks) description, every index checked before use."""
    nbblocks = reader.int("nbblocks", low=0, high=n * n)
    M = np.zeros((n, n))
    if nbblocks == 0:  # Siconos reads nothing more: M = 0
        return M
    rows_b = reader.int("blocknumber0", low=1, high=n)
    cols_b = reader.int("blocknumber1", low=1, high=n)
    if nbblocks > rows_b * cols_b:
        reader.fail(f"nbblocks = {nbblocks} must be <= blocknumber0 x blocknumber1 = {rows_b * cols_b}")
    row_ends = _cumulative_sizes(reader, rows_b, n, "row")
    col_ends = _cumulative_sizes(reader, cols_b, n, "column")
    reader.int("filled1", low=rows_b + 1, high=rows_b + 1, hint="blocknumber0 + 1 block-row pointers")
    reader.int("filled2", low=nbblocks, high=nbblocks, hint="one block-column index per block, nbblocks")
    row_ptr = [reader.int("block-row pointer 0", low=0, high=0)]
    for r in range(1, rows_b + 1):
        low, high = row_ptr[-1], min(nbblocks, row_ptr[-1] + cols_b)
        if r == rows_b:
            low = high = nbblocks
        row_ptr.append(reader.int(f"block-row pointer {r}", low=low, high=high,
                                  hint=(f"the last = nbblocks = {nbblocks}, at most blocknumber1 = {cols_b} more"
                                        if r == rows_b else
                                        f"non-decreasing by at most blocknumber1 = {cols_b}, <= nbblocks")))
    if row_ptr[-1] - row_ptr[-2] > cols_b:
        reader.fail(f"block-row pointers leave {row_ptr[-1] - row_ptr[-2]} blocks to the last block row, more than "
                    f"blocknumber1 = {cols_b}")
    col_idx = []
    for r in range(rows_b):
        previous = -1
        for _ in range(row_ptr[r], row_ptr[r + 1]):
            previous = reader.int(f"block-column index of block {len(col_idx)}", low=previous + 1, high=cols_b - 1,
                                  hint="increasing within a block row, below blocknumber1")
            col_idx.append(previous)
    row_starts = [0] + row_ends[:-1]
    col_starts = [0] + col_ends[:-1]
    block = 0
    for r in range(rows_b):
        for ptr in range(row_ptr[r], row_ptr[r + 1]):
            c = col_idx[ptr]
            reader.int("block number", low=block, high=block, hint="blocks numbered in order")
            nr, nc = row_ends[r] - row_starts[r], col_ends[c] - col_starts[c]
            values = reader.numbers(nr * nc, f"block {block}").reshape((nr, nc), order="F")
            M[row_starts[r]:row_ends[r], col_starts[c]:col_ends[c]] = values
            block += 1
    return M


def _cumulative_sizes(reader: "_Tokens", count: int, n: int, which: str) -> list[int]:
    """``count`` cumulative block sizes: strictly increasing from >= 1, the last = n."""
    ends: list[int] = []
    for i in range(count):
        low = ends[-1] + 1 if ends else 1
        high = n - (count - 1 - i)   # room for the remaining blocks, each of size >= 1
        last = i == count - 1
        ends.append(reader.int(f"cumulative {which} block size {i}", low=n if last else low, high=high,
                               hint=f"strictly increasing, the last = n = {n}" if last else "strictly increasing"))
    return ends


class _Tokens:
    """The file's tokens, converted one at a time as the reader needs them; errors name the token's position."""

    def __init__(self, text: str, name: str):
        self.text, self.name = text, name
        self._matches = _TOKEN.finditer(text)
        self.index = 0          # tokens consumed (the last one read is token ``index``, counting from 1)
        self.offset = 0         # character offset just after the last token read
        self._start = 0         # character offset of the last token read

    def _where(self) -> str:
        return f"token {self.index}, line {self.text.count(chr(10), 0, self._start) + 1}"

    def fail(self, message: str) -> NoReturn:
        raise LCPError(f"{self.name}: {message} ({self._where()})")

    def _next(self, what: str) -> str:
        match = next(self._matches, None)
        if match is None:
            raise LCPError(f"{self.name}: file ends while reading {what} (after {self.index} tokens)")
        self.index += 1
        self._start, self.offset = match.start(), match.end()
        return match.group()

    def _bad(self, token: str, what: str, kind: str) -> NoReturn:
        line = self.text.count("\n", 0, self._start) + 1
        raise LCPError(f"{self.name}: token {token!r} at position {self.index} (line {line}) is not {kind} "
                       f"(reading {what})")

    def int(self, what: str, low: int | None = None, high: int | None = None, hint: str = "") -> int:
        token = self._next(what)
        if not _INT.match(token):
            self._bad(token, what, "an integer")
        if len(token.lstrip("+-")) > _INT_DIGITS:     # int() of 4,300+ digits raises Python's limit, naming nothing
            self.fail(f"{what} must be an integer of at most {_INT_DIGITS} digits; got one of "
                      f"{len(token.lstrip('+-'))} digits")
        value = int(token)
        if (low is not None and value < low) or (high is not None and value > high):
            if low is not None and high is not None and low == high:
                bounds = f"= {low}"
            elif high is None:
                bounds = f">= {low}"
            else:
                bounds = f"in [{low}, {high}]"
            self.fail(f"{what} must be {bounds}" + (f" ({hint})" if hint else "") + f"; got {value}")
        return value

    def numbers(self, count: int, what: str) -> np.ndarray:
        remaining = len(self.text) - self.offset
        if remaining < 2 * count - 1:   # every number takes a character and a separator: refuse before allocating
            raise LCPError(f"{self.name}: file ends while reading {what} (needs {count} numbers after token "
                           f"{self.index}; only {remaining} characters remain)")
        out = np.empty(count)
        for i in range(count):
            token = self._next(what)
            value = float(token.replace("d", "e").replace("D", "e")) if _FLOAT.match(token) else float("nan")
            if not math.isfinite(value):
                self._bad(token, what, "a finite number")
            out[i] = value
        return out
