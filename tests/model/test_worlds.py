"""Map worlds: PGM reading, run merging, world boxes (pure logic, no mujoco), and a build from a
map."""

import numpy as np
import pytest

from amr_twin.model.occupancy_map import load_map, merge_boxes, wall_boxes, world_xml
from amr_twin.model.pgm import read_pgm, write_pgm


def _map(tmp_path, image, origin=(-1.0, -2.0, 0.0), negate=0, res=0.1):
    write_pgm(tmp_path / "m.pgm", image)
    (tmp_path / "m.yaml").write_text(
        f"image: m.pgm\nresolution: {res}\norigin: {list(origin)}\nnegate: {negate}\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    return tmp_path / "m.yaml"


def test_pgm_round_trip_and_ascii(tmp_path):
    img = np.arange(12, dtype=np.uint8).reshape(3, 4) * 20
    write_pgm(tmp_path / "a.pgm", img)
    assert np.array_equal(read_pgm(tmp_path / "a.pgm"), img)
    (tmp_path / "b.pgm").write_text("P2\n# comment\n2 2\n255\n0 254\n100 7\n")
    assert read_pgm(tmp_path / "b.pgm").tolist() == [[0, 254], [100, 7]]


def test_merged_boxes_cover_exactly_the_occupied_cells():
    rng = np.random.default_rng(3)
    occ = rng.random((40, 50)) < 0.3
    occ[5:15, 10:30] = True  # a big block must become few boxes
    cover = np.zeros(occ.shape, int)
    boxes = merge_boxes(occ)
    for r, c, nr, nc in boxes:
        cover[r : r + nr, c : c + nc] += 1
    assert np.array_equal(cover, occ.astype(int))  # exact cover, no overlap
    assert len(boxes) < occ.sum() / 2
    block = np.zeros((20, 20), bool)
    block[2:12, 3:9] = True
    assert merge_boxes(block) == [(2, 3, 10, 6)]


def test_thresholds_negate_and_world_coordinates(tmp_path):
    img = np.full((10, 20), 254, np.uint8)
    img[0, :] = 0  # top row: y from 0.9 to 1.0 above the origin
    img[5:7, 2] = 100  # p = 0.61 < 0.65: free
    grid = load_map(_map(tmp_path, img))
    assert grid.occupied.sum() == 20
    ((centre, half, yaw),) = wall_boxes(grid, wall_height_m=2.0)
    assert centre == pytest.approx([-1.0 + 1.0, -2.0 + 0.95, 1.0])
    assert half == pytest.approx([1.0, 0.05, 1.0]) and yaw == 0.0
    negated = load_map(_map(tmp_path, 255 - img, negate=1))
    assert np.array_equal(negated.occupied, grid.occupied)


def test_map_modes(tmp_path):
    image = np.full((4, 4), 0, np.uint8)
    image[0, :] = 100  # raw: 100 % occupied
    image[1, :] = 255  # raw: unknown
    write_pgm(tmp_path / "m.pgm", image)
    base = (
        "image: m.pgm\nresolution: 0.1\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: "
        "0.196\n"
    )
    (tmp_path / "raw.yaml").write_text(base + "mode: raw\n")
    assert load_map(tmp_path / "raw.yaml").occupied.sum(axis=1).tolist() == [
        4,
        0,
        0,
        0,
    ]  # image rows
    (tmp_path / "scale.yaml").write_text(base + "mode: scale\nnegate: 0\n")
    assert load_map(tmp_path / "scale.yaml").occupied.sum() == 8  # the black rows 2 and 3
    (tmp_path / "bad.yaml").write_text(base + "mode: fancy\n")
    with pytest.raises(ValueError, match="mode 'fancy'"):
        load_map(tmp_path / "bad.yaml")


def test_rotated_origin_rotates_the_boxes(tmp_path):
    img = np.full((10, 10), 254, np.uint8)
    img[9, 0] = 0  # lower-left pixel: centre at (0.05, 0.05) in the map frame
    grid = load_map(_map(tmp_path, img, origin=(1.0, 0.0, np.pi / 2)))
    ((centre, _, yaw),) = wall_boxes(grid)
    assert centre[:2] == pytest.approx([1.0 - 0.05, 0.05]) and yaw == pytest.approx(np.pi / 2)
    assert 'euler="0 0 90"' in world_xml(tmp_path / "m.yaml")


def test_shipped_example_map_builds():
    from amr_twin.model.build import build
    from amr_twin.model.config import load_config
    from amr_twin.model.paths import ROOT

    path = ROOT / "models" / "worlds" / "room_map.yaml"
    assert len(merge_boxes(load_map(path).occupied)) < 20
    model = build(load_config(), world=path).model
    names = [model.geom(i).name for i in range(model.ngeom)]
    assert sum(n.startswith("wall_") for n in names) == len(merge_boxes(load_map(path).occupied))


def _write_map(tmp_path, yaml_text, pgm=None):
    if pgm is not None:
        (tmp_path / "m.pgm").write_bytes(pgm)
    (tmp_path / "m.yaml").write_text(yaml_text)
    return tmp_path / "m.yaml"


@pytest.mark.parametrize(
    "yaml_text, pgm, text",
    [
        ("image: gone.pgm\nresolution: 0.05\n", None, "m.yaml: image "),
        (
            "image: m.pgm\norigin: [0, 0, 0]\n",
            b"P5\n2 2\n255\n\x00\x00\x00\x00",
            "m.yaml: resolution is missing",
        ),
        (
            "image: m.pgm\nresolution: -0.05\n",
            b"P5\n2 2\n255\n\x00\x00\x00\x00",
            "resolution: -0.05 must be in (0, 100]",
        ),
        (
            "image: m.pgm\nresolution: 0.05\norigin: [0, 0]\n",
            b"P5\n2 2\n255\n\x00\x00\x00\x00",
            "origin: [0, 0] must be",
        ),
        (
            "image: m.pgm\nresolution: 0.05\n",
            b"P5\n100 100\n255\nabc",
            "m.pgm: truncated PGM (3 of 10000",
        ),
        ("image: m.pgm\nresolution: 0.05\n", bytes(range(7, 200)), "m.pgm: not a PGM image"),
        ("image: m.pgm\nresolution: 0.05\n", b"P5\n2", "m.pgm: not a PGM image (header ends"),
        ("resolution: 0.05\n", None, "m.yaml: image is missing"),
        ("- a list\n", None, "expected a map_server mapping"),
    ],
)
def test_map_errors_are_one_line_naming_the_file(tmp_path, yaml_text, pgm, text):
    from amr_twin.model.worlds import MapError

    path = _write_map(tmp_path, yaml_text, pgm)
    with pytest.raises(MapError) as exc:
        load_map(path)
    assert text in str(exc.value) and "\n" not in str(exc.value)


def test_a_malformed_mjcf_world_is_named(tmp_path):
    from typer.testing import CliRunner

    from amr_twin.cli.main import app

    bad = tmp_path / "bad.xml"
    bad.write_text('<mujoco><worldbody><geom type="plane" size="1 1 1"</worldbody></mujoco>')
    res = CliRunner().invoke(app, ["run", "stop", "--world", str(bad)])
    assert res.exit_code == 2 and f"--world {bad}: not a valid MJCF world" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1


def test_worlds_declare_their_start_pose():
    from amr_twin.model.worlds import default_start

    assert default_start("warehouse") == (-6.0, 0.0, 0.0)
    assert default_start("empty") == (0.0, 0.0, 0.0) and default_start("nowhere.xml") == (
        0.0,
        0.0,
        0.0,
    )


def test_charging_stations_as_the_world_declares_them(tmp_path):
    from amr_twin.model.worlds import ChargingStation, MapError, charging_stations

    assert charging_stations("warehouse") == (
        ChargingStation("charger-1", -8.6, 6.2, 1.5707963),
        ChargingStation("charger-2", -7.4, 6.2, 1.5707963),
    )
    assert [s.name for s in charging_stations("aisles")] == ["charger-1", "charger-2"]
    assert charging_stations("corridor") == () and charging_stations("room_map.yaml") == ()
    bad = tmp_path / "bad.xml"
    bad.write_text(
        '<mujoco><custom><numeric name="charging_station:x" data="1 2"/></custom></mujoco>'
    )
    with pytest.raises(MapError, match="charging_station:x must hold x_m y_m yaw_rad"):
        charging_stations(bad)
