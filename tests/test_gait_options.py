"""One gait vocabulary: every verb that solves gaits takes every gait option with the same name
and default, the core's request has each field with that default, and the constants the light
parser keeps agree with the modules they come from (over the parsers, no solve)."""

from __future__ import annotations

import dataclasses
import math
import shlex

import pytest

from biped_gait.arguments import request_fields
from biped_gait.cli_parser import GAIT_VERBS, MAP_STRIDE, MAX_CASES, MOMENTUM_RATE, PUSH_DIRECTIONS, PUSH_PHASE, build_parser
from biped_gait.core.dynamics.impulses import COORDINATES, EFFORTS
from biped_gait.core.dynamics.settings import DEFAULTS
from biped_gait.core.gait.bvp import CLOSURES
from biped_gait.core.gait.planner import GaitRequest
from biped_gait.core.walking.steering import DEFAULT_RATE
from biped_gait.gait_options import ALPHA_RANGE_DEG, MARGINS, MODES, OPTION_BY_NAME, OPTIONS, POINT
from biped_gait.studies import maps, push_study
from biped_gait.studies.sweep import MAX_CASES as SWEEP_MAX_CASES

pytestmark = pytest.mark.core

# A value other than the default for every option, as a user types it.
GIVEN = {"mode": "anti-normal", "params": "aoustin2013-table", "closure": "slack", "effort": "l2",
         "effort_coordinates": "absolute", "friction": "inf", "rate_bound": "12", "min_clearance": "0.004",
         "friction_margin": "0.1", "step_width": "0.3", "turn_radius": "2.5"}
RANGE_VERBS = ("sweep", "optimize-arms", "figure", "maps", "push-study")  # take --alpha-deg-range A B STEP
FIRST = {"figure": ["fig4"]}  # a verb's positional arguments


def parse(verb: str, *args: str):
    return build_parser().parse_args([*verb.split(), *FIRST.get(verb, []), *args])


def test_the_vocabulary_is_the_core_requests():
    fields = {f.name: f for f in dataclasses.fields(GaitRequest)}
    for option in (*POINT, *OPTIONS):
        assert option.name in fields, option.name
        default = fields[option.name].default
        if option.name == "params":
            assert default == ""  # the planner's own set, DEFAULT_PARAMS for a planner built with none
        elif option.name == "mode":
            assert default.value == option.default
        elif option.name not in ("step_length", "period", "arm_amplitude"):
            assert default == option.default or (math.isnan(default) and math.isnan(option.default)), option.name
    assert set(fields) == {o.name for o in (*POINT, *OPTIONS)}, "a GaitRequest field the vocabulary does not have"
    assert OPTION_BY_NAME["closure"].choices == CLOSURES and OPTION_BY_NAME["effort"].choices == EFFORTS
    assert OPTION_BY_NAME["effort_coordinates"].choices == COORDINATES
    assert MODES == ("normal", "anti-normal") and set(MARGINS) <= set(OPTION_BY_NAME)
    assert math.radians(ALPHA_RANGE_DEG[1]) == pytest.approx(DEFAULTS.arm_range[1], abs=1e-15)
    assert math.radians(ALPHA_RANGE_DEG[2]) == pytest.approx(DEFAULTS.arm_coarse_step, abs=1e-15)


@pytest.mark.parametrize("verb", GAIT_VERBS)
def test_every_verb_takes_every_gait_option_with_the_same_default(verb):
    defaults = parse(verb)
    for option in OPTIONS:
        value = getattr(defaults, option.name)
        if option.name == "mode" and verb in ("sweep", "atlas build"):
            value = value[0] if verb == "sweep" else value  # a list of modes
            if verb == "atlas build":
                assert value == list(MODES)  # an atlas per mode (the planner needs both)
                continue
        assert value == option.default or (math.isnan(value) and math.isnan(option.default)), (verb, option.name)
    given = parse(verb, *[arg for name, text in GIVEN.items() for arg in (OPTION_BY_NAME[name].cli_flag, text)])
    fields = request_fields(given, exclude=())
    for name, text in GIVEN.items():
        value = fields[name]
        expected = text if isinstance(OPTION_BY_NAME[name].default, str) else float(text)
        assert value == expected or value == [expected], (verb, name, value)
    assert parse(verb, "--json", "-").json == "-"
    assert parse(verb, "--out", "somewhere").out is not None


@pytest.mark.parametrize("verb", RANGE_VERBS)
def test_amplitude_ranges_are_spelled_alike(verb):
    args = parse(verb, "--alpha-deg-range", "5", "40", "2.5")
    assert args.alpha_deg_range == [5.0, 40.0, 2.5]


@pytest.mark.parametrize("line, message", [
    ("plan --arm-amplitude 20", "unrecognized arguments: --arm-amplitude"),
    ("optimize-arms --alpha-range 0 45", "unrecognized arguments: --alpha-range"),
    ("urdf --output x.urdf", "unrecognized arguments: --output"),
    ("sweep --mode sideways", "argument --mode: invalid choice"),
])
def test_the_old_dialects_are_gone(capsys, line, message):
    with pytest.raises(SystemExit) as exit_:
        build_parser().parse_args(shlex.split(line))
    assert exit_.value.code == 2 and message in capsys.readouterr().err


def test_the_parsers_constants_are_the_studies():
    assert PUSH_DIRECTIONS == tuple(push_study.STUDY_DIRECTIONS)
    assert PUSH_PHASE == push_study.PHASE and MOMENTUM_RATE == DEFAULT_RATE and MAX_CASES == SWEEP_MAX_CASES
    assert MAP_STRIDE == maps.MAP_STRIDE


def test_0_means_unset_where_0_is_not_a_value_the_same_on_every_verb():
    """A friction coefficient, a joint-rate bound, a step width or a turn radius of 0 is the
    unset value (a message field cannot default to NaN or inf): the verbs resolve it as the
    service, the action and the simulator do (``resolve_unset``); every other 0 is itself."""
    fields = request_fields(parse("plan", "--friction", "0", "--rate-bound", "0", "--step-width", "0",
                                  "--turn-radius", "0", "--min-clearance", "0"))
    assert math.isnan(fields["friction"]) and math.isinf(fields["rate_bound"]) and math.isnan(fields["step_width"])
    assert math.isinf(fields["turn_radius"]) and fields["min_clearance"] == 0.0
    assert {o.name for o in OPTIONS if o.unset is not None} == {"friction", "rate_bound", "step_width", "turn_radius"}
    assert math.isinf(request_fields(parse("plan", "--turn-radius", "nan"))["turn_radius"])
    assert request_fields(parse("plan", "--friction", "0.3"))["friction"] == 0.3
