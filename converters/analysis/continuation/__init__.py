"""Periodic orbits along a parameter path: pseudo-arclength continuation, bifurcations, branch switching.

A family is a problem per parameter value p, a method, and the orbit's period k in switching periods. Its
orbits solve F(x, p) = P^k(x; p) - x = 0, P the method's one-period (stroboscopic) map with its Jacobian J
(exact for the event method: state-transition and saltation matrices; :mod:`.periodic`). Continuation
works in scaled variables z = (x / x_scale, p / p_scale) so that state and parameter count alike:

* predictor z + ds t along the unit tangent t, the null vector of [J - I, F_p] (F_p by a central
  difference in p);
* corrector: Newton on [F(x, p); t . (z - z_pred)] = 0 (pseudo-arclength: it passes folds, where p
  turns back);
* step ds grows after quick corrections, shrinks after slow or failed ones, bounded by ``max_step`` in p.

Between consecutive orbits the Floquet multipliers mu (eigenvalues of J) give the test functions

    period doubling   det(J + I)                         a real multiplier crosses -1
    fold              det(J - I)                         a real multiplier crosses +1
    Neimark-Sacker    max |mu| - 1 over complex pairs    a complex pair crosses the unit circle

and each orbit's *signature*, the sequence of its events over the k periods (switchings with the
configuration entered, activations and releases of each complementarity pair), changes at a border
collision: a switching instant reaching the period boundary (the ramp's limit: a switching skipped), a
new crossing, a pair's current grazing zero (the CCM/DCM boundary). A change of sign or of signature is
located by bisection on the chord between the two orbits (the orbit at each midpoint solved on the plane
normal to the chord, so that folds bisect too) to ``locate_tol``. A test function that changes sign at
a change of signature is a multiplier jumping at the border collision (a non-smooth bifurcation), not a
smooth one, and is reported as part of that border collision.

After a period doubling on which the period-k orbit loses stability, the period-2k orbit is born with
the tangent (v, 0), v the eigenvector of the multiplier -1: the 2k-family has a pitchfork there. A
pseudo-arclength step along (v, 0) lands on the new branch, which is then followed in turn
(:func:`switch_branch`, :func:`cascade`).

An orbit that meets one more condition c(p, x) = 0 (an impact at a corner of the constraint, where J jumps but
the signature does not change) is solved with its parameter by Newton on [F; c] (:func:`locate_condition`).
"""
from __future__ import annotations

from .branching import cascade, switch_branch
from .condition import locate_condition
from .family import (KINDS, TEST_NAMES, Bifurcation, Branch, OrbitFamily, OrbitPoint, check_path,
                     test_functions)
from .tracing import follow

__all__ = ["OrbitFamily", "OrbitPoint", "Bifurcation", "Branch", "follow", "switch_branch", "cascade",
           "test_functions", "check_path", "KINDS", "TEST_NAMES"]
