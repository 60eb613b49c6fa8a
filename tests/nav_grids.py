"""Synthetic maps for the navigation tests: corridors and rooms drawn on a grid."""

import numpy as np

from amr_twin.navigation.static_map import StaticMap

RES = 0.05


def room(width_m: float = 12.0, height_m: float = 8.0, walls=()) -> StaticMap:
    """A closed room ``width_m`` x ``height_m`` (origin at its lower-left corner) with a 0.1 m wall
    around, and extra walls ``(x0, y0, x1, y1)`` (m) drawn as filled rectangles."""
    cols, rows = int(round(width_m / RES)), int(round(height_m / RES))
    occ = np.zeros((rows, cols), bool)
    occ[:2], occ[-2:], occ[:, :2], occ[:, -2:] = True, True, True, True
    for x0, y0, x1, y1 in walls:
        occ[
            int(round(y0 / RES)) : int(round(y1 / RES)), int(round(x0 / RES)) : int(round(x1 / RES))
        ] = True
    return StaticMap(occ, np.zeros_like(occ), RES, (0.0, 0.0), "synthetic room")


def two_corridors() -> StaticMap:
    """A 12 x 8 m room split by a wall at y = 3.5..4.5 from x = 2 to 10: two 2 m wide corridors
    joined at both ends."""
    return room(
        12.0, 8.0, walls=[(2.0, 3.5, 10.0, 4.5), (2.0, 0.0, 10.0, 1.5), (2.0, 6.5, 10.0, 8.0)]
    )


def write_map(folder, name: str, static: StaticMap):
    """Save ``static`` as a map_server YAML + PGM (0 occupied, 254 free) in ``folder``; its YAML
    path."""
    import yaml

    from amr_twin.model.pgm import write_pgm

    image = np.where(static.occupied, 0, 254).astype(np.uint8)[::-1]
    write_pgm(folder / f"{name}.pgm", image)
    meta = {
        "image": f"{name}.pgm",
        "resolution": static.resolution_m,
        "origin": [static.origin_xy_m[0], static.origin_xy_m[1], 0.0],
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
        "negate": 0,
    }
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(meta))
    return path


def random_warehouse(seed: int) -> StaticMap:
    """A warehouse the code has never seen: a 20 x 14 m hall (origin at its centre) with rack rows
    of random count, length and depth, aisles 2.0 to 2.6 m, cross aisles at both ends, drawn from
    ``seed``."""
    rng = np.random.default_rng(seed)
    walls = []
    n_rows = int(rng.integers(2, 4))
    depth = rng.uniform(0.8, 1.2, n_rows)
    aisle = rng.uniform(2.0, 2.6, n_rows + 1)
    total = depth.sum() + aisle.sum()
    y = 7.0 - (14.0 - total) / 2 - aisle[0]
    x0, x1 = -10.0 + rng.uniform(2.5, 3.5), 10.0 - rng.uniform(2.5, 3.5)
    for k in range(n_rows):
        gap = rng.uniform(x0 + 3.0, x1 - 3.0)  # a cross aisle through the row, 2.2 m wide
        walls += [
            (x0 + 10, y - depth[k] + 7, gap - 1.1 + 10, y + 7),
            (gap + 1.1 + 10, y - depth[k] + 7, x1 + 10, y + 7),
        ]
        y -= depth[k] + aisle[k + 1]
    hall = room(20.0, 14.0, walls=walls)
    return StaticMap(hall.occupied, hall.unknown, RES, (-10.0, -7.0), f"random warehouse {seed}")
