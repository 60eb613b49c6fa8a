"""The chapter 5 figures: published samples drawn as samples, the thesis' bands where they are
scored."""

import pytest

import amr_twin.experiments.runner.executor as executor
from amr_twin.experiments.chapter5 import experiment as chapter5
from amr_twin.model.config import load_config


@pytest.fixture(scope="module")
def run5_figure():
    """Run 5 (the right wheel starts 1.6 s after the command): the figure as drawn, not saved."""
    results = chapter5.run(load_config(), runs=[5], duration_s=6.0, progress=False)
    figures = []
    real = executor.save_figure
    executor.save_figure = lambda fig, path, dpi=110: figures.append(fig)
    try:
        chapter5.plot(results, "unused")
    finally:
        executor.save_figure = real
    return results, figures[0]


def test_published_samples_are_markers_from_the_first_sample(run5_figure):
    """The samples were joined to (0, 0) by a line, so a wheel at rest until 1.6 s
    seemed to rise from t = 0 (runs 5 and 8)."""
    results, fig = run5_figure
    raw = results["runs"][0]["raw"]
    for ax, w in zip(fig.axes, (0, 1)):
        pub = raw["published"][w]
        (markers,) = [ln for ln in ax.lines if ln.get_marker() == "o"]
        assert markers.get_linestyle() == "None"
        assert list(markers.get_xdata()) == pytest.approx(
            pub[:, 0].tolist()
        )  # the samples, nothing at t = 0
        held = [
            ln
            for ln in ax.lines
            if ln.get_drawstyle() == "steps-post" and ln.get_color() == markers.get_color()
        ]
        assert held and min(held[0].get_xdata()) == pytest.approx(
            pub[0, 0]
        )  # held from the first sample on
    assert raw["published"][1][0, 0] > 1.5  # the right wheel's first sample comes late


def test_the_thesis_bands_are_drawn_with_their_source(run5_figure):
    _, fig = run5_figure
    for ax in fig.axes:
        labels = ax.get_legend_handles_labels()[1]
        assert any(label.startswith("thesis bands (§5.1.3, fig. 5.3): delay") for label in labels)
        assert any(
            label.startswith("peak ") and "over the final value" in label for label in labels
        )
        assert any(label.startswith("steady error -4 to +4 RPM") for label in labels)
    left, right = (
        next(x for x in ax.get_legend_handles_labels()[1] if x.startswith("thesis"))
        for ax in fig.axes
    )
    assert left.endswith("delay 0.3-0.7 s at 50 %") and right.endswith(
        "delay 0.1-0.3 s at 50 %"
    )  # 99.2, 60.8 RPM


def test_each_band_has_its_own_colour_and_the_earliest_first_sample_is_marked(run5_figure):
    """The bands were all one green; the time before one revolution at the reference (listing 4.12)
    is hatched, named in the legend and annotated, one revolution after the command."""
    from amr_twin.experiments.chapter5.figure import BAND_STYLE, CAPTION

    results, fig = run5_figure
    assert len({colour for colour, _ in BAND_STYLE.values()}) == len(BAND_STYLE)
    t0 = results["runs"][0]["raw"]["t_command_s"]
    for ax, rpm in zip(fig.axes, (99.20, 60.80)):
        labels = ax.get_legend().get_texts()
        named = [t.get_text() for t in labels]
        assert (
            f"no published sample before {60 / rpm:.2f} s (one revolution, listing 4.12)" in named
        )
        assert any(p.get_hatch() == BAND_STYLE["first_sample"][1] for p in ax.patches)
        (line,) = [ln for ln in ax.lines if ln.get_linestyle() == "-."]
        assert line.get_xdata()[0] == pytest.approx(t0 + 60 / rpm)
        assert any(t.get_text().startswith("earliest first sample") for t in ax.texts)
    assert any(t.get_text() == CAPTION for t in fig.texts)
