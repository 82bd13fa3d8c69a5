"""The solver tables of the report time the solves: every solver is loaded (compiled by numba, or read from its
cache) by a warm-up before the first timed run, with the same kinds of arguments."""
import numpy as np

from validation import peer


def test_every_method_is_warmed_up_on_both_paths_before_the_first_timed_solve(monkeypatch):
    calls = []

    def recorded(M, q, **kwargs):
        calls.append((M.shape[0], kwargs["method"], kwargs["tol"], kwargs["fast_paths"], M.dtype, q.dtype))
        return peer_solve(M, q, **kwargs)
    peer_solve = peer.solve_lcp
    monkeypatch.setattr(peer, "solve_lcp", recorded)
    M, q = np.array([[4.0, 1.0, 0.0], [1.0, 4.0, 1.0], [0.0, 1.0, 4.0]]), -np.ones(3)
    rows = peer.solver_table([("tridiagonal", M, q)], tol=1e-8)
    assert [r["status"] for r in rows] == ["solved"] * len(peer.METHODS)
    warm = [(k, method, 1e-8, False, np.float64, np.float64) for k in (2, 3) for method in peer.METHODS]
    assert calls == warm + [(3, method, 1e-8, False, np.float64, np.float64) for method in peer.METHODS]
