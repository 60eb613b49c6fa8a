"""``--record DIR`` / ``--mcap DIR`` on ``experiment chapter5`` (and ``sweep payload``'s refusal):
one recording per run.

The recordings are read back with the formats' own readers (rerun's ``RrdReader``,
``mcap``); the results must be the same with and without recording.
"""

import collections
import json

import numpy as np
import pyarrow as pa
import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.model.config import load_config
from amr_twin.experiments.chapter5 import experiment as chapter5

CH5_RUNS, CH5_DURATION_S = [1, 3], 2.0


def rrd_summary(path):
    """Rows per entity and the last ``sim_time`` in the file, ns."""
    from rerun.chunk import RrdReader

    rows, last_ns = collections.Counter(), 0
    for chunk in RrdReader(str(path)).stream().to_chunks():
        rows[str(chunk.entity_path)] += chunk.num_rows
        batch = chunk.to_record_batch()
        if "sim_time" in batch.schema.names and batch.num_rows:
            last_ns = max(last_ns, max(batch.column("sim_time").cast(pa.int64()).to_pylist()))
    return rows, last_ns


def mcap_counts(path):
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    topics = {c.id: c.topic for c in summary.channels.values()}
    return {topics[cid]: n for cid, n in summary.statistics.channel_message_counts.items()}


def _without_wall(obj):
    if isinstance(obj, dict):
        return {k: _without_wall(v) for k, v in obj.items() if k != "wall_s"}
    if isinstance(obj, list):
        return [_without_wall(v) for v in obj]
    return obj


@pytest.fixture(scope="module")
def cfg():
    return load_config()


@pytest.fixture(scope="module")
def chapter5_cli(tmp_path_factory):
    """Chapter 5 runs 1 and 3 through the CLI, two worker processes, both recordings into one
    folder."""
    base = tmp_path_factory.mktemp("ch5rec")
    res = CliRunner().invoke(
        app,
        [
            "experiment",
            "chapter5",
            "--out",
            str(base / "out"),
            "--runs",
            "1,3",
            "--duration-s",
            str(CH5_DURATION_S),
            "--jobs",
            "2",
            "--record",
            str(base / "rec"),
            "--mcap",
            str(base / "rec"),
            "--no-progress",
        ],
    )
    assert res.exit_code == 0, res.output
    return base, res


def test_chapter5_one_recording_per_run(chapter5_cli):
    base, res = chapter5_cli
    rec = base / "rec"
    assert sorted(p.name for p in rec.iterdir()) == [
        "run1.mcap",
        "run1.rrd",
        "run3.mcap",
        "run3.rrd",
    ]
    for n in CH5_RUNS:
        rows, last_ns = rrd_summary(rec / f"run{n}.rrd")
        assert last_ns == pytest.approx(
            CH5_DURATION_S * 1e9, abs=1e6
        )  # the whole run on the timeline
        assert (
            rows["/wheels/left/true_rpm"] == CH5_DURATION_S * 100 + 1
        )  # 100 Hz recorder rows, t = 0 included
        assert "/world/bodies/amr/base_link" in rows and "/commands" in rows
        counts = mcap_counts(rec / f"run{n}.mcap")
        assert abs(counts["/odom"] - 50 * CH5_DURATION_S) <= 1
        assert counts["/wheel_Command"] == 1
    assert "run<N>.rrd for runs 1,3" in res.output
    # the runs and the simulated time it states are those it ran (runs 1 and 3: no study runs)
    assert f"for 2 runs, {2 * CH5_DURATION_S:.0f} simulated s (jobs 2" in res.output
    assert "on the published samples (true speed " in res.output


def test_chapter5_terminal_opens_with_the_findings_then_the_counts(chapter5_cli):
    """The findings first, one line each as in report.md, the pointer to
    docs/explanation/validation.md, then one line of passes per metric instead of a MISS line per
    run and wheel."""
    from amr_twin.experiments.chapter5.findings import VALIDATION_DOC, lines

    base, res = chapter5_cli
    found = json.loads((base / "out" / "metrics.json").read_text())["findings"]
    out = res.output.splitlines()
    expected = lines(found)
    assert out[0].startswith("chapter 5 findings (faithful firmware; details in ")
    assert out[1 : 1 + len(expected)] == ["  " + line for line in expected] and len(expected) == 7
    assert out[1 + len(expected)].startswith(f"  why: {VALIDATION_DOC}")
    assert out[2 + len(expected)].startswith("published checks passed by metric: delay_s ")
    assert "MISS" not in res.output


def test_chapter5_results_identical_with_and_without_recording(cfg, chapter5_cli):
    base, _res = chapter5_cli
    plain = chapter5.report(
        chapter5.run(cfg, runs=CH5_RUNS, duration_s=CH5_DURATION_S, progress=False), base / "plain"
    ).as_json()
    recorded = json.loads((base / "out" / "metrics.json").read_text())
    assert _without_wall(recorded["runs"]) == _without_wall(json.loads(json.dumps(plain["runs"])))
    assert recorded["summary"] == plain["summary"]


def test_chapter5_recording_in_process_same_series(cfg, tmp_path):
    plain = chapter5.run(cfg, runs=[3], duration_s=2.0, progress=False)["runs"][0]["raw"]
    recorded = chapter5.run(cfg, runs=[3], duration_s=2.0, progress=False, record_dir=tmp_path)[
        "runs"
    ][0]["raw"]
    for key in ("t_s", "true_rpm", "pwm_counts"):
        assert np.array_equal(plain[key], recorded[key]), key
    assert len(plain["published"][0]) >= 1
    assert all(np.array_equal(a, b) for a, b in zip(plain["published"], recorded["published"]))
    assert [p.name for p in tmp_path.iterdir()] == ["run3.rrd"]


def test_record_option_takes_a_folder(tmp_path):
    res = CliRunner().invoke(
        app,
        [
            "experiment",
            "chapter5",
            "--out",
            str(tmp_path / "o"),
            "--record",
            str(tmp_path / "run.rrd"),
        ],
    )
    assert res.exit_code == 2 and "--record" in res.output and "folder" in res.output
    (tmp_path / "file").write_text("x")
    res = CliRunner().invoke(
        app, ["sweep", "payload", "--out", str(tmp_path / "s"), "--mcap", str(tmp_path / "file")]
    )
    assert res.exit_code == 2 and "--mcap" in res.output and "not a folder" in res.output
    assert not (tmp_path / "o").exists() and not (tmp_path / "s").exists()


def test_an_unwritable_out_folder_is_refused_before_the_work(tmp_path, monkeypatch):
    def read_only(*args, **kwargs):
        raise OSError(30, "Read-only file system")

    monkeypatch.setattr("tempfile.mkstemp", read_only)
    res = CliRunner().invoke(app, ["experiment", "fusion", "--out", str(tmp_path / "f")])
    assert res.exit_code == 2 and "Read-only file system" in res.stderr and "--out" in res.stderr
