"""Sliding-mode control of the boost (REFERENCE section 5): the hysteresis controller with sub-step
switching instants, the implicit relay LCP, the PI outer loop with a load step, and ngspice."""
import numpy as np
import pytest

from converters.errors import ParameterError
from converters.lcp import solve_lcp
from converters.models.sliding import iref0, predicted_frequency, resolve_smc, simulate_smc
from netlists import build_smc_netlist
from validation.scenes import SCENE_DIR, load_scene


def test_a_request_where_sliding_cannot_exist_is_refused():
    with pytest.raises(ParameterError, match=r"Vref must be above Vin = 10 V .*got Vref = 10 V"):
        resolve_smc({"Vref": 10})
    with pytest.raises(ParameterError, match=r"Vref must be above Vin = 24 V .*got Vref = 20 V"):
        simulate_smc({"Vin": 24})
    with pytest.raises(ParameterError, match="t_step and R_step go together"):
        resolve_smc({"t_step": "5m"})
    with pytest.raises(ParameterError, match=r"band \(hysteresis half-band on the current error\) must be in \(0, inf\)"):
        resolve_smc({"band": 0})
    with pytest.raises(ParameterError, match=r"h must be in \(0, 5e-07\] s"):
        simulate_smc({}, h=1e-6)
    with pytest.raises(ParameterError, match="Vref"):
        build_smc_netlist({"Vref": "20\n.control\nshell touch /tmp/x\n.endc"}, 1e-3)


def test_hysteresis_controller_regulates_and_switches_at_the_predicted_frequency():
    run = simulate_smc({}, t_end=30e-3)
    s = run.summary()
    assert s["vout_mean"] == pytest.approx(20.0, rel=1e-4)                  # Iref = Vref^2/(R Vin) = 1 A
    assert s["switching_frequency_Hz"] == pytest.approx(predicted_frequency(run.params, s["vout_mean"]), rel=1e-3)
    assert s["switching_frequency_Hz"] == pytest.approx(50e3, rel=1e-3)
    # Switching instants are placed inside the step: the current turns exactly at Iref +- band.
    w = run.window(28e-3)
    assert run.x[w, 0].max() == pytest.approx(iref0(run.params) + 0.05, abs=2e-6)
    assert run.x[w, 0].min() == pytest.approx(iref0(run.params) - 0.05, abs=2e-6)
    assert not run.active[:, 0].any()   # the diode never blocks a current: no DCM under this control


def test_switching_frequency_does_not_depend_on_the_step_beyond_its_own_accuracy():
    """With the crossing placed inside the step, h = T_sw/100 already gives the frequency to 1e-3."""
    f = [simulate_smc({}, h=h, t_end=20e-3).switching_frequency(18e-3) for h in (2e-7, 1e-7, 2e-8)]
    assert max(f) / min(f) - 1.0 < 1e-3


def test_implicit_relay_step_is_the_reference_lcp_and_the_clip_formula():
    rng = np.random.default_rng(5)
    Vin, L, h = 10.0, 1e-3, 1e-6
    for _ in range(50):
        i, v, iref = rng.uniform(0.5, 1.5), rng.uniform(11, 30), rng.uniform(0.5, 1.5)
        m, q = h * v / L, -(i + h * Vin / L - iref)
        # REFERENCE 5: M' = [[M, I], [-I, 0]], q' = [q + M lb; ub - lb] with lb = 0, ub = 1.
        result = solve_lcp(np.array([[m, 1.0], [-1.0, 0.0]]), np.array([q, 1.0]), method="lemke")
        assert result.solved
        clip = np.clip((i + h * Vin / L - iref) * L / (h * v), 0.0, 1.0)
        assert result.z[0] == pytest.approx(clip, abs=1e-12)


def test_implicit_variant_settles_at_vin_over_v_without_chatter():
    run = simulate_smc({}, scheme="implicit", t_end=30e-3)
    s = run.summary(2e-3)
    assert abs(s["lambda_mean"] - s["vin_over_v"]) <= 1e-6
    assert s["lambda_spread"] <= 1e-6                                     # no switching chatter
    lam = 1.0 - run.switch[run.window(28e-3)]
    assert ((lam > 0.0) & (lam < 1.0)).all()                               # inside the band, not on a bound
    assert s["vout_mean"] == pytest.approx(20.0, rel=5e-3)


def test_pi_loop_restores_vref_after_the_load_halves():
    p = {"Ki": 100, "t_step": 15e-3, "R_step": 20}
    for scheme in ("hysteresis", "implicit"):
        run = simulate_smc(p, scheme=scheme, t_end=40e-3)
        s = run.summary(2e-3)
        assert s["vout_mean"] == pytest.approx(20.0, rel=1e-3)
        assert 5e-3 < s["recovery_time_s"] < 15e-3
        # Without the integral the current reference stays at Vref^2/(R Vin): v falls to sqrt(Iref R_step Vin).
    plain = simulate_smc({"t_step": 15e-3, "R_step": 20}, t_end=40e-3).summary(2e-3)
    assert plain["vout_mean"] == pytest.approx(np.sqrt(1.0 * 20 * 10), rel=2e-3)


@pytest.mark.usefixtures("ngspice")
@pytest.mark.parametrize("name", ["boost-smc", "boost-smc-load-step", "boost-smc-implicit"])
def test_sliding_mode_scenes_pass_in_both_simulators(name):
    from validation.suite import run_scene
    result = run_scene(load_scene(SCENE_DIR / f"{name}.toml"))
    assert result.ok, result.reason
    m = result.metrics
    if name == "boost-smc-implicit":
        assert m["lambda_minus_vin_over_v"] <= 1e-6 and m["lambda_spread"] <= 1e-6
        return
    assert m["vout_ref_rel_lcp"] <= 5e-3 and m["vout_ref_rel_spice"] <= 5e-3
    assert m["frequency_rel_lcp"] <= 0.05 and m["frequency_rel_spice"] <= 0.05
    assert m["frequency_lcp_vs_spice"] <= 0.05
    if name == "boost-smc-load-step":
        assert np.isfinite(m["recovery_lcp_s"]) and np.isfinite(m["recovery_spice_s"])
        assert m["recovery_lcp_vs_spice"] <= 0.1
