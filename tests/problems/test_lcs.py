"""LCS problems, schedules and methods: construction and validation."""
import numpy as np
import pytest

from converters.errors import ParameterError
from converters.problems import Configuration, LCSProblem, Schedule
from converters.methods import BackwardEuler, Theta
from converters.methods.theta import time_grid

A2 = np.zeros((2, 2))


def config(**over):
    base = dict(A=A2, B=[[1.0], [0.0]], C=[[1.0, 0.0]], D=[[0.0]])
    base.update(over)
    return Configuration(**base)


@pytest.mark.parametrize("over,match", [
    (dict(A=np.zeros((2, 3))), r"A must be square \(n x n\); got shape 2x3"),
    (dict(B=[[1.0], [0.0], [2.0]]), r"B must have shape 2xany; got shape 3x1"),
    (dict(C=[[1.0, 0.0, 0.0]]), r"C must have shape 1x2; got shape 1x3"),
    (dict(D=np.zeros((2, 2))), r"D must have shape 1x1; got shape 2x2"),
    (dict(A=[[np.nan, 0.0], [0.0, 0.0]]), r"A must contain only finite numbers; got nan at index \(0, 0\)"),
    (dict(E=[1.0, 2.0, 3.0]), r"E must be a vector of length 2; got shape 3"),
    (dict(F=[np.inf]), r"F must contain only finite numbers; got inf"),
])
def test_configuration_rejects_bad_matrices(over, match):
    with pytest.raises(ParameterError, match=match):
        config(**over)


@pytest.mark.parametrize("kwargs,match", [
    (dict(h=0.0), r"h must be positive \(> 0 s\); got 0.0"),
    (dict(h=-1e-6), r"h must be positive \(> 0 s\); got -1e-06"),
    (dict(h=float("nan")), r"h must be a finite number; got nan"),
    (dict(h=1e-6, theta=0.4), r"theta must be in \[0.5, 1\]; got 0.4"),
    (dict(h=1e-6, theta=1.2), r"theta must be in \[0.5, 1\]; got 1.2"),
])
def test_methods_reject_bad_options(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        Theta(**kwargs)
    assert issubclass(ParameterError, ValueError)


def test_methods_accept_spice_suffixes_and_backward_euler_is_theta_one():
    assert Theta("10n").h == pytest.approx(1e-8)
    assert BackwardEuler(1e-6).theta == 1.0


def test_problem_rejects_mismatched_configurations_and_bad_x0():
    other = Configuration(A=np.zeros((3, 3)), B=np.ones((3, 1)), C=np.ones((1, 3)), D=[[0.0]], name="big")
    with pytest.raises(ParameterError, match=r"configuration 'big' has n = 3, k = 1, the first n = 2, k = 1"):
        LCSProblem((config(), other), Schedule.pwm(1e-5, 0.5), x0=[0, 0], t_span=(0, 1e-4))
    with pytest.raises(ParameterError, match=r"x0 must be a vector of length 2; got shape 3"):
        LCSProblem((config(),), Schedule.constant(), x0=[0, 0, 0], t_span=(0, 1e-4))
    with pytest.raises(ParameterError, match=r"t_end > t_start = 0 s; got t_end = -1"):
        LCSProblem((config(),), Schedule.constant(), x0=[0, 0], t_span=(0, -1))
    with pytest.raises(ParameterError, match=r"switching configs must be indices in \[0, 0\]; got 1"):
        LCSProblem((config(),), Schedule.pwm(1e-5, 0.5), x0=[0, 0], t_span=(0, 1e-4))


@pytest.mark.parametrize("duty,configs", [(0.0, (1,)), (1.0, (0,)), (0.25, (0, 1))])
def test_pwm_schedule_handles_duty_zero_and_one(duty, configs):
    schedule = Schedule.pwm(1e-5, duty)
    assert schedule.configs == configs
    assert schedule.config_at(np.array([0.1e-5, 0.9e-5, 1.1e-5])).tolist() == (
        [0, 1, 0] if duty == 0.25 else [configs[0]] * 3)


def test_pwm_rejects_impossible_duty():
    with pytest.raises(ParameterError, match=r"D \(duty ratio\) must be in \[0, 1\]; got 1.5"):
        Schedule.pwm(1e-5, 1.5)


def test_switching_instants_are_grid_points():
    problem = LCSProblem((config(), config(name="off")), Schedule.pwm(1e-5, 0.3), x0=[0, 0], t_span=(0, 5e-5))
    t = time_grid(problem, 0.7e-6)
    for m in range(5):
        for instant in (m * 1e-5, m * 1e-5 + 0.3e-5):
            assert np.min(np.abs(t - instant)) < 1e-18
    assert np.diff(t).max() <= 0.7e-6 * (1 + 1e-12)
    assert np.diff(t).min() > 0.7e-9  # points within h/1000 of an instant are merged


@pytest.mark.parametrize("build,message", [
    (lambda: Schedule(1.0, (0, np.nan), (0, 1)), "schedule start must be a finite number; got nan"),  # never applied
    (lambda: Schedule(np.nan, (0,), (0,)), "schedule period must be a positive number of seconds, or inf"),
    (lambda: Schedule(1.0, (0, 0.5), (0.7, 1.9)), "schedule config must be an integer >= 0; got 0.7"),  # int() before
    (lambda: Schedule.pwm(1.0, 0.5, 2.7, 1), "schedule config must be an integer >= 0; got 2.7"),
])
def test_a_schedule_refuses_what_it_would_truncate_or_ignore(build, message):
    with pytest.raises(ParameterError) as refused:
        build()
    assert str(refused.value).startswith(message)
