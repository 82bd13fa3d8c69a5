"""The pure-Python LCP methods the compiled ones replaced, kept only as the test oracle.

Each is the former implementation, line for line (numpy, no deadline): the compiled method must take
the same path (status, iterations) and reach the same z on the same problem (test_compiled.py).
"""
from __future__ import annotations

from itertools import combinations

import numpy as np

from converters.lcp.result import FAILED, MAX_ITERATIONS, NO_SOLUTION, SOLVED, check_solution, finish, lcp_error


def accepts(M, q, z, tol) -> bool:
    with np.errstate(all="ignore"):
        w = q + M @ z
        return not check_solution(M, q, z, w, lcp_error(M, q, z), tol)


def lemke(M, q, *, tol, max_iter, pivot_tol=1e-13):
    k = q.shape[0]
    if np.all(q >= 0.0):
        return finish(M, q, np.zeros(k), status=SOLVED, iterations=0, method="lemke", tol=tol)
    z0_col, rhs_col = 2 * k, 2 * k + 1
    tableau = np.zeros((k, 2 * k + 2))
    tableau[:, :k] = np.eye(k)
    tableau[:, k:2 * k] = -M
    tableau[:, z0_col] = -1.0
    tableau[:, rhs_col] = q
    basis = np.arange(k)
    row = _lexmin_rows(tableau, np.arange(k), z0_col, k, sign=-1.0)
    entering = z0_col
    iterations = 0
    while True:
        leaving = basis[row]
        _pivot(tableau, row, entering)
        basis[row] = entering
        iterations += 1
        if leaving == z0_col:
            return _lemke_result(M, q, tableau, basis, iterations, tol, SOLVED)
        entering = leaving + k if leaving < k else leaving - k
        if iterations >= max_iter:
            return _lemke_result(M, q, tableau, basis, iterations, tol, MAX_ITERATIONS)
        column = tableau[:, entering]
        scale = max(1.0, np.abs(column).max())
        candidates = np.flatnonzero(column > pivot_tol * scale)
        if candidates.size == 0:
            return _lemke_result(M, q, tableau, basis, iterations, tol, NO_SOLUTION)
        ratios = tableau[candidates, rhs_col] / column[candidates]
        best = ratios.min()
        z0_rows = candidates[(basis[candidates] == z0_col) & (ratios <= best + 1e-12 * max(1.0, abs(best)))]
        row = z0_rows[0] if z0_rows.size else _lexmin_rows(tableau, candidates, entering, k)


def _lexmin_rows(tableau, rows, col, k, sign=1.0):
    rhs_col = 2 * k + 1
    keys = np.column_stack([tableau[rows, rhs_col], tableau[rows, :k]]) / (sign * tableau[rows, col])[:, None]
    remaining = np.arange(rows.size)
    for j in range(keys.shape[1]):
        values = keys[remaining, j]
        low = values.min()
        remaining = remaining[values <= low + 1e-11 * max(1.0, abs(low))]
        if remaining.size == 1:
            break
    return rows[remaining[0]]


def _pivot(tableau, row, col):
    tableau[row] /= tableau[row, col]
    factors = tableau[:, col].copy()
    factors[row] = 0.0
    tableau -= np.outer(factors, tableau[row])


def _lemke_result(M, q, tableau, basis, iterations, tol, status):
    k = q.shape[0]
    z = np.zeros(k)
    values = tableau[:, 2 * k + 1]
    for row, var in enumerate(basis):
        if k <= var < 2 * k:
            z[var - k] = values[row]
    z = np.maximum(z, 0.0) if status == SOLVED else z
    return finish(M, q, z, status=status, iterations=iterations, method="lemke", tol=tol)


def murty(M, q, *, tol, max_iter):
    k = q.shape[0]
    in_basis = np.zeros(k, dtype=bool)
    z = np.zeros(k)
    scale = 1e-12 * (1.0 + np.abs(q).max())
    for iteration in range(max_iter + 1):
        z = np.zeros(k)
        if in_basis.any():
            sub = M[np.ix_(in_basis, in_basis)]
            try:
                z[in_basis] = np.linalg.solve(sub, -q[in_basis])
            except np.linalg.LinAlgError:
                return finish(M, q, z, status=FAILED, iterations=iteration, method="murty", tol=tol)
        w = q + M @ z
        basic_values = np.where(in_basis, z, w)
        negative = np.flatnonzero(basic_values < -scale)
        if negative.size == 0:
            return finish(M, q, np.maximum(z, 0.0), status=SOLVED, iterations=iteration, method="murty", tol=tol)
        if iteration == max_iter:
            break
        in_basis[negative[0]] = ~in_basis[negative[0]]
    return finish(M, q, z, status=MAX_ITERATIONS, iterations=max_iter, method="murty", tol=tol)


def pgs(M, q, *, tol, max_iter, omega=1.0):
    k = q.shape[0]
    diag = np.diag(M).copy()
    if np.any(diag <= 0.0):
        return finish(M, q, np.zeros(k), status=FAILED, iterations=0, method="pgs", tol=tol)
    z = np.zeros(k)
    rows = [M[i] for i in range(k)]
    with np.errstate(over="ignore", invalid="ignore"):
        for sweep in range(1, max_iter + 1):
            for i in range(k):
                wi = q[i] + rows[i] @ z
                z[i] = max(0.0, z[i] - omega * wi / diag[i])
            if not np.all(np.isfinite(z)):
                return finish(M, q, np.zeros(k), status=FAILED, iterations=sweep, method="pgs", tol=tol)
            if accepts(M, q, z, tol):
                return finish(M, q, z, status=SOLVED, iterations=sweep, method="pgs", tol=tol)
    return finish(M, q, z, status=MAX_ITERATIONS, iterations=max_iter, method="pgs", tol=tol)


def newton_fb(M, q, *, tol, max_iter, rho=1e-10, p=2.1, beta=0.5, sigma=1e-4):
    k = q.shape[0]
    z = np.zeros(k)
    eye = np.eye(k)
    for iteration in range(1, max_iter + 1):
        w = q + M @ z
        phi, jac = _fb_and_jacobian(z, w, M, eye)
        psi = 0.5 * phi @ phi
        grad = jac.T @ phi
        try:
            direction = np.linalg.solve(jac, -phi)
            if grad @ direction > -rho * np.linalg.norm(direction) ** p:
                direction = -grad
        except np.linalg.LinAlgError:
            direction = -grad
        step = 1.0
        while step > 1e-14:
            trial = z + step * direction
            phi_t = _fb(trial, q + M @ trial)
            if 0.5 * phi_t @ phi_t <= psi + sigma * step * (grad @ direction):
                break
            step *= beta
        else:
            return finish(M, q, z, status=FAILED, iterations=iteration, method="newton", tol=tol)
        z = trial
        if accepts(M, q, np.maximum(z, 0.0), tol):
            return finish(M, q, np.maximum(z, 0.0), status=SOLVED, iterations=iteration, method="newton", tol=tol)
    return finish(M, q, np.maximum(z, 0.0), status=MAX_ITERATIONS, iterations=max_iter, method="newton", tol=tol)


def _fb(z, w):
    return np.sqrt(z * z + w * w) - z - w


def _fb_and_jacobian(z, w, M, eye):
    norm = np.sqrt(z * z + w * w)
    phi = norm - z - w
    safe = norm > 1e-300
    da = np.where(safe, z / np.where(safe, norm, 1.0), 1.0 / np.sqrt(2.0)) - 1.0
    db = np.where(safe, w / np.where(safe, norm, 1.0), 1.0 / np.sqrt(2.0)) - 1.0
    return phi, da[:, None] * eye + db[:, None] * M


def enumerate_bases(M, q, *, tol):
    k = q.shape[0]
    qscale = max(1.0, float(np.abs(q).max()))
    solutions = []
    visited = 0
    for size in range(k + 1):
        for subset in combinations(range(k), size):
            visited += 1
            z = np.zeros(k)
            if size:
                J = list(subset)
                sub = M[np.ix_(J, J)]
                if np.linalg.cond(sub) > 1e12:
                    continue
                z[J] = np.linalg.solve(sub, -q[J])
            w = q + M @ z
            feasible_tol = 1e-9 * max(qscale, float(np.abs(z).max(initial=0.0)))
            if np.all(z >= -feasible_tol) and np.all(w >= -feasible_tol):
                z = np.maximum(z, 0.0)
                if not any(np.allclose(z, s, rtol=1e-9, atol=1e-12 * qscale) for s in solutions):
                    solutions.append(z)
    if not solutions:
        return finish(M, q, np.zeros(k), status=NO_SOLUTION, iterations=visited, method="enum", tol=tol)
    best = min(solutions, key=lambda s: float(s @ s))
    result = finish(M, q, best, status=SOLVED, iterations=visited, method="enum", tol=tol, solutions=solutions)
    if result.status == FAILED:
        best = min(solutions, key=lambda s: lcp_error(M, q, s))
        result = finish(M, q, best, status=SOLVED, iterations=visited, method="enum", tol=tol, solutions=solutions)
    return result


REFERENCE = {"lemke": lemke, "murty": murty, "pgs": pgs, "newton": newton_fb, "enum": enumerate_bases}
