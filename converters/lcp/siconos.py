"""Reader for the Siconos numerics ``.dat`` LCP format (dense and sparse-block storage).

Layout: n, storage (0 dense, 1 sparse-block), size0 size1; dense: size0 size1 again and the matrix
column-major; sparse-block: block counts, cumulative row/column block sizes, block-row pointers,
block-column indices, then each block (its number and nr*nc numbers, column-major). Then q.
Anything after q is free text (kept as ``comment``).
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import LCPError

_FLOAT = re.compile(r"^[+-]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][+-]?\d+)?$")


@dataclass(frozen=True)
class LCPFile:
    name: str
    M: np.ndarray
    q: np.ndarray
    comment: str


def read_siconos_lcp(path) -> LCPFile:
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise LCPError(f"FILE must be a readable Siconos .dat LCP file; got {str(path)!r} ({exc.strerror})") from None
    tokens = text.split()
    numbers = []
    for tok in tokens:
        if not _FLOAT.match(tok):
            break
        numbers.append(float(tok.replace("d", "e").replace("D", "e")))
    reader = _Numbers(numbers, path)
    n = reader.int("n")
    storage = reader.int("storage type")
    size0, size1 = reader.int("size0"), reader.int("size1")
    if size0 != size1 or size0 != n or n < 1:
        raise LCPError(f"{path.name}: sizes must agree (n = size0 = size1 >= 1); got {n}, {size0}, {size1}")
    if storage == 0:
        reader.int("size0"), reader.int("size1")
        M = np.array(reader.take(n * n, "M")).reshape((n, n), order="F")
    elif storage == 1:
        M = _read_sparse_block(reader, n)
    else:
        raise LCPError(f"{path.name}: storage type must be 0 (dense) or 1 (sparse-block); got {storage}")
    q = np.array(reader.take(n, "q"))
    consumed = reader.position
    comment = " ".join(tokens[consumed:])
    return LCPFile(name=path.stem.removeprefix("lcp_"), M=M, q=q, comment=comment)


def _read_sparse_block(reader, n):
    nbblocks = reader.int("nbblocks")
    rows_b, cols_b = reader.int("blocknumber0"), reader.int("blocknumber1")
    row_ends = [reader.int("row block size") for _ in range(rows_b)]
    col_ends = [reader.int("column block size") for _ in range(cols_b)]
    filled1, filled2 = reader.int("filled1"), reader.int("filled2")
    row_ptr = [reader.int("block-row pointer") for _ in range(filled1)]
    col_idx = [reader.int("block-column index") for _ in range(filled2)]
    M = np.zeros((n, n))
    row_starts = [0] + row_ends[:-1]
    col_starts = [0] + col_ends[:-1]
    block = 0
    for block_row in range(rows_b):
        for ptr in range(row_ptr[block_row], row_ptr[block_row + 1] if block_row + 1 < filled1 else filled2):
            block_col = col_idx[ptr]
            reader.int("block number")
            nr = row_ends[block_row] - row_starts[block_row]
            nc = col_ends[block_col] - col_starts[block_col]
            values = np.array(reader.take(nr * nc, "block")).reshape((nr, nc), order="F")
            M[row_starts[block_row]:row_ends[block_row], col_starts[block_col]:col_ends[block_col]] = values
            block += 1
    if block != nbblocks:
        raise LCPError(f"sparse-block file: expected {nbblocks} blocks; read {block}")
    return M


class _Numbers:
    def __init__(self, numbers, path):
        self.numbers, self.position, self.path = numbers, 0, path

    def take(self, count, what):
        if self.position + count > len(self.numbers):
            raise LCPError(f"{self.path.name}: file ends while reading {what} "
                           f"(needs {count} numbers at position {self.position})")
        out = self.numbers[self.position:self.position + count]
        self.position += count
        return out

    def int(self, what):
        value = self.take(1, what)[0]
        if value != int(value):
            raise LCPError(f"{self.path.name}: {what} must be an integer; got {value}")
        return int(value)
