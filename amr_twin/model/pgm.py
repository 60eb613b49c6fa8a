"""PGM images (binary P5 and ASCII P2), the pixels of a map_server map
(:mod:`amr_twin.model.occupancy_map`): read with their header checked, written as P5."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from amr_twin.model.worlds import MapError

MAX_MAP_PIXELS = 25_000_000
"""Largest map image, pixels (5000 x 5000): every occupied run becomes a MuJoCo geom."""


def _pgm_tokens(data: bytes, path) -> tuple[list[bytes], int]:
    """The four header tokens (magic, width, height, maxval) and the offset after them."""
    tokens: list[bytes] = []
    pos, n = 0, len(data)
    while len(tokens) < 4:  # magic, width, height, maxval (comments start with #)
        while pos < n and data[pos : pos + 1].isspace():
            pos += 1
        if pos >= n:
            raise MapError(f"{path}: not a PGM image (header ends after {len(tokens)} of 4 fields)")
        if data[pos : pos + 1] == b"#":
            newline = data.find(b"\n", pos)
            if newline < 0:
                raise MapError(f"{path}: not a PGM image (unterminated comment in the header)")
            pos = newline + 1
            continue
        end = pos
        while end < n and not data[end : end + 1].isspace():
            end += 1
        tokens.append(data[pos:end])
        pos = end
    return tokens, pos


def read_pgm(path: str | Path) -> np.ndarray:
    """Read a binary (P5) or ASCII (P2) 8-bit PGM image as a (rows, cols) uint8 array.

    Raises :class:`MapError` (one line naming the file) for anything else.
    """
    from amr_twin.model.yaml_file import read_bytes

    try:  # a regular file of a bounded size: /dev/zero or a pipe is refused, not read or waited on
        data = read_bytes(path, "", MapError, limit=MAX_MAP_PIXELS + 4096)
    except MapError as exc:
        raise MapError(f"{exc} (the map image)") from None
    tokens, pos = _pgm_tokens(data, path)
    magic = tokens[0]
    if magic not in (b"P5", b"P2"):
        raise MapError(f"{path}: not a PGM image (magic {magic[:8]!r}, expected P5 or P2)")
    try:
        width, height, maxval = (int(t) for t in tokens[1:])
    except ValueError:
        raise MapError(
            f"{path}: not a PGM image (width, height and maxval must be integers)"
        ) from None
    if width <= 0 or height <= 0 or not 0 < maxval <= 255:
        raise MapError(
            f"{path}: only 8-bit PGM images with a positive size are supported "
            f"({width} x {height}, maxval {maxval})"
        )
    if width * height > MAX_MAP_PIXELS:
        raise MapError(
            f"{path}: {width} x {height} pixels; at most {MAX_MAP_PIXELS:,} (each wall run is a "
            f"geom)"
        )
    if magic == b"P5":
        if len(data) < pos + 1 + width * height:
            raise MapError(
                f"{path}: truncated PGM ({len(data) - pos - 1} of {width * height} pixel bytes)"
            )
        pixels = np.frombuffer(data, np.uint8, width * height, pos + 1)
    else:
        try:
            values = np.array(data[pos:].split(), dtype=np.int64)
        except ValueError:
            raise MapError(f"{path}: ASCII PGM pixels must be integers") from None
        if len(values) < width * height or (values < 0).any() or (values > maxval).any():
            raise MapError(f"{path}: ASCII PGM needs {width * height} pixels in 0..{maxval}")
        pixels = values[: width * height].astype(np.uint8)
    return pixels.reshape(height, width).copy()


def write_pgm(path: str | Path, image: np.ndarray) -> None:
    """Write a (rows, cols) uint8 array as a binary P5 PGM."""
    image = np.asarray(image, np.uint8)
    Path(path).write_bytes(b"P5\n%d %d\n255\n" % (image.shape[1], image.shape[0]) + image.tobytes())
