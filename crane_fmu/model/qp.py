"""A small dense convex QP solver in plain Python, for the model-predictive controller inside the FMUs.

Solves::

    minimise    1/2 x' H x + f' x
    subject to  lower_i <= r_i' x <= upper_i   for every constraint row r_i

with ``H`` symmetric positive definite and fixed (factored once by :func:`prepare`),
``f`` and the bounds given per solve. The method is the primal active-set method in
its range-space form (Nocedal and Wright, *Numerical Optimization*, 2nd ed., 2006,
Algorithm 16.3, with ``H^-1`` as in Section 16.5 and Goldfarb and Idnani's use of it):
every iterate is feasible and the objective never rises, so a solve stopped at its
iteration cap still has a feasible point, the best one it reached. It starts from a
feasible point the caller gives and a guess of the active set (warm start).

The working set ``W`` of rows held at a bound gives the equality-constrained minimiser
``x_W = x_u - H^-1 R_W' lam`` with ``x_u = -H^-1 f`` and ``(R_W H^-1 R_W') lam = R_W x_u - b_W``;
the Cholesky factor of ``R_W H^-1 R_W'`` grows by one row when a row joins ``W``.

Every sum runs left to right in explicit loops (never ``sum()``, whose float
rounding changed in CPython 3.12), so the C port (``fmu_src/models/qp.c``) gives
the same bits on the same platform.
"""

import math
from collections import namedtuple
from functools import reduce
from itertools import accumulate
from operator import add, mul

from .linalg import total

Prepared = namedtuple("Prepared", "n h hinv rows chains norms g s")
Prepared.__doc__ = ("A QP's fixed part: its size ``n``, ``H`` and ``H^-1`` (lists of rows), the constraint rows as "
                    "``(first, values)`` (the non-zero span of each row), their chains (:func:`chains`), their "
                    "1-norms, ``G = R H^-1`` and ``S = R H^-1 R'``.")

Solution = namedtuple("Solution", "x active iterations optimal")
Solution.__doc__ = ("The solution ``x``; ``active``: the rows held at a bound, as ``(row, side)`` with side +1 at "
                    "the upper and -1 at the lower bound; ``iterations``; ``optimal``: False when the cap stopped "
                    "it (``x`` is then feasible but not optimal).")

FEASIBLE = 1e-9  # a start may violate a bound by this much (relative to the bound's scale)
PARALLEL = 1e-12  # a step this short (relative to x), or a row's change along it this small, is rounding


def cholesky(a):
    """The lower-triangular ``L`` with ``L L' = a`` for a symmetric positive definite ``a``.

    Raises
    ------
    ArithmeticError
        When ``a`` is not positive definite.
    """
    n = len(a)
    factor = [[0.0] * n for _ in range(n)]
    for i in range(n):
        row = factor[i]
        for j in range(i + 1):
            other = factor[j]
            acc = a[i][j]
            for k in range(j):
                acc -= row[k] * other[k]
            if i == j:
                if not acc > 0.0:
                    raise ArithmeticError("the matrix is not positive definite")
                row[i] = math.sqrt(acc)
            else:
                row[j] = acc / other[j]
    return factor


def inverse_spd(a):
    """``a^-1`` for a symmetric positive definite ``a``, through its Cholesky factor."""
    factor = cholesky(a)
    n = len(a)
    # L^-1 by forward substitution, column by column
    linv = [[0.0] * n for _ in range(n)]
    for j in range(n):
        linv[j][j] = 1.0 / factor[j][j]
        for i in range(j + 1, n):
            acc = 0.0
            for k in range(j, i):
                acc -= factor[i][k] * linv[k][j]
            linv[i][j] = acc / factor[i][i]
    # a^-1 = L^-T L^-1
    result = [[0.0] * n for _ in range(n)]
    for i in range(n):
        for j in range(i + 1):
            acc = 0.0
            for k in range(i, n):
                acc += linv[k][i] * linv[k][j]
            result[i][j] = result[j][i] = acc
    return result


def span_dot(first, values, x):
    """``r' x`` for a row given by its non-zero span ``values`` starting at ``first``, added left to right."""
    return reduce(add, map(mul, values, x[first:first + len(values)]), 0.0)


def chains(rows):
    """The rows in runs ``(first row, last row)`` where each row is the one before it plus one more element.

    Along such a run (the speed rows of a move: prefix sums) every product ``r' x``
    is the one before plus one term, the same sum left to right as :func:`span_dot`'s.
    """
    runs, begin = [], 0
    for i in range(1, len(rows) + 1):
        if i == len(rows) or not (rows[i][0] == rows[i - 1][0] and len(rows[i][1]) == len(rows[i - 1][1]) + 1
                                  and rows[i][1][:-1] == rows[i - 1][1]):
            runs.append((begin, i - 1))
            begin = i
    return runs


def row_products(prepared, x):
    """``[r' x for every row]``, each the left-to-right sum of :func:`span_dot`, in one pass per chain."""
    rows, out = prepared.rows, []
    for begin, end in prepared.chains:
        first, values = rows[begin]
        head = len(values)
        out.append(span_dot(first, values, x))
        if end > begin:
            tail = rows[end][1][head:]
            out.extend(accumulate(map(mul, tail, x[first + head:first + head + len(tail)]), initial=out.pop()))
    return out

def prepare(h, rows):
    """The fixed part of a QP: ``H`` (n x n, positive definite) and its constraint rows ``[(first, values)]``.

    Raises
    ------
    ArithmeticError
        When ``H`` is not positive definite.
    """
    hinv = inverse_spd(h)
    n = len(h)
    rows = [(first, list(values)) for first, values in rows]
    runs = chains(rows)
    g = [[span_dot(first, values, hinv[j]) for j in range(n)] for first, values in rows]  # H^-1 is symmetric
    norms = [total([abs(v) for v in values]) for _, values in rows]
    prepared = Prepared(n, [list(row) for row in h], hinv, rows, runs, norms, g, None)
    return prepared._replace(s=[row_products(prepared, gi) for gi in g])


def objective(h, f, x):
    """``1/2 x' H x + f' x``."""
    return total([0.5 * total([hij * xj for hij, xj in zip(row, x)]) * xi + fi * xi
                  for row, xi, fi in zip(h, x, f)])


def _append(factor, working, s, row):
    """Grow the Cholesky factor of ``S_W`` by ``row``; False (and nothing changed) when it depends on ``W``."""
    column = s[row]
    new = []
    for i, other in enumerate(factor):
        acc = column[working[i]]
        for k in range(i):
            acc -= new[k] * other[k]
        new.append(acc / other[i])
    acc = column[row]
    for value in new:
        acc -= value * value
    if not acc > 1e-12 * column[row]:
        return False
    new.append(math.sqrt(acc))
    factor.append(new)
    working.append(row)
    return True


def cholesky_solve(factor, rhs):
    """``y`` with ``L L' y = rhs`` for the Cholesky factor ``L`` (:func:`cholesky`)."""
    m = len(factor)
    y = [0.0] * m
    for i in range(m):
        acc = rhs[i]
        row = factor[i]
        for k in range(i):
            acc -= row[k] * y[k]
        y[i] = acc / row[i]
    lam = [0.0] * m
    for i in range(m - 1, -1, -1):
        acc = y[i]
        for k in range(i + 1, m):
            acc -= factor[k][i] * lam[k]
        lam[i] = acc / factor[i][i]
    return lam


def solve(prepared, f, lower, upper, start, hint=(), max_iterations=100):
    """Minimise from the feasible ``start``; ``hint``: rows ``[(row, side)]`` guessed active (warm start).

    Parameters
    ----------
    prepared : Prepared
        From :func:`prepare`.
    f, lower, upper : sequence of float
        The linear term and each row's bounds (``-inf``/``inf``: none; ``lower == upper``: an equality).
    start : sequence of float
        A feasible point (each row within its bounds, to rounding).
    hint : iterable of (int, int)
        Rows held at their upper (+1) or lower (-1) bound at the start, if they are at it there.
    max_iterations : int
        The cap; at the cap the solve returns its feasible point with ``optimal`` False.

    Returns
    -------
    Solution
    """
    n, _, hinv, rows, _, norms, g, s = prepared
    x = list(start)
    xu = [-span_dot(0, hrow, f) for hrow in hinv]  # the unconstrained minimiser -H^-1 f
    rx = row_products(prepared, x)
    rxu = None  # r' xu for every row, when first needed
    working, sides, factor = [], [], []
    for row, side in hint:
        bound = upper[row] if side > 0 else lower[row]
        if abs(rx[row] - bound) <= FEASIBLE * (1.0 + abs(bound)) and row not in working \
                and _append(factor, working, s, row):
            sides.append(side)
    iterations = 0
    while iterations < max_iterations:
        iterations += 1
        # the minimiser on the working set, and its multipliers
        target, lam = xu, []
        if working:
            if rxu is None:
                rxu = row_products(prepared, xu)
            lam = cholesky_solve(factor, [rxu[row] - (upper[row] if side > 0 else lower[row])
                                        for row, side in zip(working, sides)])
            for li, row in zip(lam, working):
                target = [t - li * gj for t, gj in zip(target, g[row])]
        p = [t - xj for t, xj in zip(target, x)]
        # the longest step towards it that keeps every other row within its bounds
        alpha, blocking, blocking_side = 1.0, -1, 0
        rp = row_products(prepared, p)
        held, count = set(working), len(rows)
        longest = max(map(abs, p))
        if longest <= PARALLEL * (1.0 + max(map(abs, x))):  # x is the minimiser on W already
            count = 0
        small = PARALLEL * longest  # along p, rows that depend on W change by rounding only
        for row in range(count):
            change = rp[row]
            if abs(change) <= small * norms[row] or row in held:
                continue
            if change > 0.0:
                slack, side = upper[row] - rx[row], 1
            else:
                slack, side = lower[row] - rx[row], -1
            ratio = slack / change
            if ratio < alpha:
                alpha, blocking, blocking_side = (ratio if ratio > 0.0 else 0.0), row, side
        if blocking >= 0:
            x = [a + alpha * b for a, b in zip(x, p)]
            rx = [a + alpha * b for a, b in zip(rx, rp)]
            if _append(factor, working, s, blocking):
                sides.append(blocking_side)
                continue
            # a row that depends on W blocks only by rounding: x is as good as stationary on W
        else:
            x = list(target)
            rx = [a + b for a, b in zip(rx, rp)]
        # stationary on the working set: optimal when every multiplier has its bound's sign
        worst, drop = 0.0, -1
        for i, side in enumerate(sides):
            signed = lam[i] * side
            if signed < worst and lower[working[i]] != upper[working[i]]:  # an equality stays
                worst, drop = signed, i
        if drop < 0:
            return Solution(x, list(zip(working, sides)), iterations, True)
        kept_rows, kept_sides = working[drop + 1:], sides[drop + 1:]
        del working[drop:], sides[drop:], factor[drop:]
        for row, side in zip(kept_rows, kept_sides):
            if _append(factor, working, s, row):
                sides.append(side)
    return Solution(x, list(zip(working, sides)), iterations, False)
