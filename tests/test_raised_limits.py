"""A resumed run may raise a point limit (``supercoil.api.recording``): which settings
differ, how the stored settings change, and which stored branches are continued,
dropped or kept. Oracle: the rules written out on hand-made settings and branches (the
runs themselves: ``test_tweezers_resume``, ``test_api_commands``,
``test_knot_diagram_resume``)."""

from types import SimpleNamespace

import pytest

from supercoil.api.recording import raised_limits, reopened, settings_mismatch
from supercoil.continuation import ContinuationStatus

FLAT = {"command": "tweezers", "max_points": 2000, "nodes": 104, "dna": {"bp": 3000}}
NESTED = {"command": "diagram ring", "options": {"contact_max_points": 40,
                                                 "secondary_max_points": 40, "modes": [2]}}


def test_a_raised_limit_is_no_difference_and_a_lowered_one_is():
    assert settings_mismatch(FLAT, {**FLAT, "max_points": 6000}) is None
    lowered = settings_mismatch(FLAT, {**FLAT, "max_points": 1000})
    assert lowered.startswith("max_points = 2000 in the file, 1000 now") and \
        "not lower it" in lowered
    # any other setting is compared as before
    assert settings_mismatch(FLAT, {**FLAT, "nodes": 105}).startswith("nodes = 104")
    nested = {**NESTED, "options": {**NESTED["options"], "contact_max_points": 39}}
    assert settings_mismatch(NESTED, nested).startswith("options.contact_max_points = 40")


@pytest.mark.parametrize("stored,given,expected", [
    (FLAT, {**FLAT, "max_points": 6000}, {**FLAT, "max_points": 6000}),
    (FLAT, FLAT, None),
    (NESTED, {"contact_max_points": 41, "secondary_max_points": 40},
     {**NESTED, "options": {**NESTED["options"], "contact_max_points": 41}}),
    # the limits are found at any depth of the given settings too
    (NESTED, {"command": "diagram ring", "options": {"secondary_max_points": 60}},
     {**NESTED, "options": {**NESTED["options"], "secondary_max_points": 60}}),
])
def test_the_stored_settings_take_the_raised_limits_only(stored, given, expected):
    assert raised_limits(stored, given) == expected


def branch(status):
    return SimpleNamespace(status=status)


def test_the_first_finished_branch_at_its_limit_is_reopened_and_those_after_dropped():
    done, limit = ContinuationStatus.PARAMETER_BOUND, ContinuationStatus.MAX_POINTS
    stored = {"circle": (branch(done), True), "alpha": (branch(ContinuationStatus.STOPPED),
                                                        True),
              "alpha_contact": (branch(limit), True), "beta": (branch(done), True),
              "beta_contact": (branch(limit), True), "knot_I+": (branch(limit), False)}
    assert reopened(stored) == (["alpha_contact"], ["beta", "beta_contact", "knot_I+"])
    # a branch in progress (published with the limit's status) is not a finished one
    assert reopened({"a": (branch(done), True), "b": (branch(limit), False)}) == ([], [])
