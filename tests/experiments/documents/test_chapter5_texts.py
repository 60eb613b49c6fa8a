"""The chapter 5 texts of the documents say what the committed scorecard holds."""

import copy
import json

from amr_twin.experiments.chapter5.scorecard import SCORECARD
from amr_twin.experiments.documents.chapter5_texts import chapter5_summary, chapter5_table


def test_the_chapter5_paragraph_says_what_the_scorecard_holds():
    card = json.loads(SCORECARD.read_text())
    text = chapter5_summary(card)
    assert f"**{card['passed']} of {card['checks_total']} checks pass**" in text
    assert f"passes {card['true_passed']} of {card['true_checks_total']}" in text
    more = copy.deepcopy(card)  # were the right wheel to overshoot 2 RPM more, the claim would turn
    more["checks"]["run2.right.overshoot"]["twin"] = (
        more["checks"]["run1.left.overshoot"]["twin"] + 2.0
    )
    assert (
        "does not overshoot more" in text
        and "overshoots more than the left, as in §5.1.3" in chapter5_summary(more)
    )
    lines = chapter5_table(card).splitlines()
    assert (
        sum(line.startswith("| ") and line[2].isdigit() for line in lines) == 14
    )  # one row per driven wheel
