"""How long compare runs ngspice towards its steady state (validation.compare.spice_steady), on stand-in runs: no
ngspice needed."""
import numpy as np
import pytest


class _NoisyRun:
    """A chunk of ngspice periods whose window's mean of vout moves by ``drift`` of its RMS (19 A) between windows:
    an inverter's load current, its mean ~0, settled but for ngspice's own switching instants."""

    def __init__(self, drift, end):
        self.drift, self.end, self.x = drift, end, np.zeros((1, 1))

    def mean(self, name, t0, t1):
        return 0.0 if t1 >= self.end - 1e-12 else self.drift * 19.0

    def rms(self, name, t0, t1):
        return 19.0


def test_ngspice_whose_drift_stops_falling_once_the_circuit_has_settled_is_not_run_to_600_periods():
    """A full bridge's load current moved 2e-4 to 1.5e-3 of its RMS from window to window in ngspice, chunk after
    chunk (its switching instants fall at its own time points), with the circuit's slowest mode decayed in one
    period (spectral radius 3.7e-6): compare ran ngspice its 600 periods from its own start and 600 again from the
    LCP's orbit (over 900 s with its refinements). Once three chunks do not halve the least drift before them, the
    run is as settled as ngspice settles it: seven chunks (the e08 drifts below: 210 periods, as measured), not
    forty."""
    from validation.compare import spice_steady
    drifts = iter([1.2e-3, 1.5e-3, 8e-4, 2.3e-4, 1.5e-3, 1.1e-3, 3.7e-4] + [1e-3] * 100)
    T, periods, window = 1 / 60, 30, 10
    calls = []

    def chunk(x0):
        calls.append(x0)
        return _NoisyRun(next(drifts), periods * T)
    run, n, drift, notes, independent = spice_steady(chunk, True, np.zeros(1), T, periods, window, "own", 3.7e-6)
    assert len(calls) == 7 and n == 210 and drift == pytest.approx(3.7e-4)
    assert notes == [] and independent is None and all(x0 is None or x0.shape == (1,) for x0 in calls[1:])
    # near the threshold a chunk may still fall below it: the voltage-mode buck's drifts, settled at its eighth
    drifts = iter([5.5e-4, 7.6e-5, 1.8e-5, 3.0e-5, 3.2e-5, 2.6e-5, 5.5e-5, 8.6e-6] + [1e-3] * 100)
    calls.clear()
    run, n, drift, notes, independent = spice_steady(chunk, True, np.zeros(1), T, periods, window, "own", 3.7e-6)
    assert len(calls) == 8 and drift == pytest.approx(8.6e-6)
    # a lightly damped circuit (its slowest mode not decayed) is run on as before: a stall is not a settling there
    drifts = iter([1e-3] * 100)
    calls.clear()
    spice_steady(chunk, True, np.zeros(1), T, periods, window, "own", 0.9999)
    assert len(calls) > 20


def test_once_the_circuit_has_decayed_ngspice_from_the_orbit_runs_one_chunk():
    """The full bridge again: its drift from window to window stays at 4.3e-5 of its RMS, below a stall's 1e-4 and
    above a settling's 1e-5, so ngspice ran its 600 periods from its own start and 600 more from the LCP's orbit
    (7.7 minutes) to compare the two means. With the circuit's slowest mode decayed over the first run, what still
    moves is ngspice's own, and one chunk from the orbit says where it settles: 21 chunks, not 40. Its own run's
    mean is already the orbit run's (equal here): that is approaching it (a strict shrink of the distance had read
    two runs equal to rounding as "NOT approaching", a FAIL)."""
    from validation.compare import MAX_SPICE_PERIODS, spice_steady
    T, periods, window = 1 / 50, 30, 10
    calls = []

    def chunk(x0):
        calls.append(x0)
        return _NoisyRun(4.3e-5, periods * T)
    run, n, drift, notes, independent = spice_steady(chunk, True, np.ones(1), T, periods, window, "own", 4.2e-18)
    assert len(calls) == MAX_SPICE_PERIODS // periods + 1 and n == periods
    assert [x0 is not None and x0.shape == (1,) and x0[0] == 1.0 for x0 in calls].count(True) == 1
    assert independent and "approaching it" in notes[0]


class _AcRun:
    """A chunk whose window's mean of vout is ``mean`` and the window's before ``before``, its RMS 3.6 A: a
    half-bridge's load current, its mean ~0."""

    def __init__(self, mean, before, end):
        self.value, self.before, self.end, self.x = mean, before, end, np.zeros((1, 1))

    def mean(self, name, t0, t1):
        return self.value if t1 >= self.end - 1e-12 else self.before

    def rms(self, name, t0, t1):
        return 3.6


def test_ngspices_distance_from_its_orbit_run_is_relative_to_an_ac_outputs_size():
    """A half-bridge's load current from ngspice's own start (rho 0.9999: not decayed in 600 periods) ends at a
    mean of -0.00688 A, 0.00689 A from the 9.68e-7 A it settles at from the LCP's orbit: the note had read that
    7.1e+03 "(relative)", against the mean; against the current's RMS (3.6 A) it is 1.9e-3."""
    from validation.compare import spice_steady
    T, periods, window = 5e-5, 30, 10
    end = periods * T

    own = iter(np.linspace(-0.02, -0.00688197, 20))          # from its own start: approaching, 20 chunks of 30

    def chunk(x0):
        if x0 is not None and x0.shape == (1,) and x0[0] == 1.0:             # from the LCP's orbit: settled
            return _AcRun(9.68e-7, 9.68e-7, end)
        mean = next(own)
        return _AcRun(mean, 1.01 * mean, end)
    run, n, drift, notes, independent = spice_steady(chunk, True, np.ones(1), T, periods, window, "own", 0.9999)
    (note,) = notes
    distance = (0.00688197 + 9.68e-7) / 3.6
    assert f"its mean of vout is -0.00688197, {distance:.2g} (relative to its size) from where it settles" in note
    assert independent


@pytest.mark.parametrize("means, moved", [
    (np.linspace(5.32, 3.4, 20), 0.03),          # one way, its drift 5.6e-3 to 8.8e-3 (below STALL_MOST) a chunk
    (3.3 + 2.0 * np.cos(np.arange(20)) * 0.9 ** np.arange(20), 0.2)])     # back and forth, 0.04 to 0.2 a chunk
def test_ngspice_still_winding_down_from_saturation_is_not_taken_for_its_own_motion(means, moved):
    """An engineer's type II loop: from rest its integrator saturates, and ngspice's vout was still at 5.32 V (it
    settles at 3.3) after 150 periods, moving 0.07 a chunk, when the orbit's small-signal mode (0.954 a period) had
    decayed to 8e-4: three chunks that did not halve the drift read as ngspice's own motion between periods, its
    window compared, and the comparison failed on ngspice's transient. A window mean moving one way chunk after
    chunk, or by more than STALL_MOST a chunk, is a transient: ngspice runs its 600 periods, then from the orbit."""
    from validation.compare import MAX_SPICE_PERIODS, spice_steady
    T, periods, window = 5e-6, 30, 10
    end = periods * T
    own = iter(means)
    calls = []

    def chunk(x0):
        calls.append(x0)
        if x0 is not None and x0.shape == (1,) and x0[0] == 1.0:             # from the LCP's orbit: settled
            return _AcRun(3.3, 3.3, end)
        mean = next(own)
        return _AcRun(mean, mean + moved, end)                 # its window before: ``moved`` V away
    run, n, drift, notes, independent = spice_steady(chunk, True, np.ones(1), T, periods, window, "own", 0.954)
    assert len(calls) == MAX_SPICE_PERIODS // periods + 1 and n == periods
    assert independent and "approaching it" in notes[0]


def test_ngspices_settling_shows_a_bar_on_a_terminal_and_nothing_in_a_pipe(monkeypatch, capsys):
    """compare's ngspice runs up to 600 periods from its own start and again from the orbit, minutes on a large
    circuit, had printed nothing until its verdict: a bar in periods on a terminal's stderr, nothing where stderr
    is a file or a pipe within PROGRESS_EVERY_S (a refusal stays one line)."""
    import io
    import sys

    from validation.compare import spice_steady
    T, periods, window = 1 / 60, 30, 10

    def chunk(x0):
        return _NoisyRun(1e-3, periods * T)

    class Terminal(io.StringIO):
        def isatty(self):
            return True
    for terminal in (True, False):
        stream = Terminal() if terminal else io.StringIO()
        monkeypatch.setattr(sys, "stderr", stream)
        spice_steady(chunk, True, None, T, periods, window, "own", 0.9999)
        shown = stream.getvalue()
        assert ("ngspice from its own start" in shown and "period" in shown) if terminal else shown == ""


def test_ngspices_long_settling_says_where_it_is_in_a_pipe(monkeypatch):
    """Two current-mode loops' compares (a slowest mode of 0.983 a period: 400 periods of ngspice, 50 a chunk) had
    printed nothing in 300 s where stderr was a pipe. Every PROGRESS_EVERY_S (here 0: every chunk) a line says how
    many periods of the most it may run, and how far its window's mean still moves."""
    import io
    import sys

    from validation import compare
    T, periods, window = 1 / 60, 30, 10
    monkeypatch.setattr(compare, "PROGRESS_EVERY_S", 0.0)
    stream = io.StringIO()
    monkeypatch.setattr(sys, "stderr", stream)
    drifts = iter([1e-3, 5e-4, 2e-4, 5e-6])
    compare.spice_steady(lambda x0: _NoisyRun(next(drifts), periods * T), True, np.zeros(1), T, periods, window,
                         "orbit", 0.5)
    lines = stream.getvalue().splitlines()
    moves = ((30, "0.001"), (60, "0.0005"), (90, "0.0002"), (120, "5e-06"))
    assert lines == [f"ngspice from pcsuite's orbit: {n} of at most 600 periods, its window mean moving {d} a chunk "
                     "(settled below 1e-05)" for n, d in moves]
