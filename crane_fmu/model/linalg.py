"""Small dense linear algebra in plain Python, for the controller designs inside the FMUs.

Matrices are lists of rows. Enough for 6 to 7 states: products, solves, the
matrix exponential and the discrete algebraic Riccati equation.
"""

import math


def zeros(n, m):
    return [[0.0] * m for _ in range(n)]


def identity(n):
    return [[1.0 if i == j else 0.0 for j in range(n)] for i in range(n)]


def transpose(a):
    return [list(row) for row in zip(*a)]


def add(a, b, scale=1.0):
    """``a + scale * b``."""
    return [[x + scale * y for x, y in zip(ra, rb)] for ra, rb in zip(a, b)]


def scaled(a, s):
    return [[s * x for x in row] for row in a]


def total(values):
    """The sum of ``values``, added left to right.

    Not ``sum()``: CPython 3.12 made it compensated for floats, so one FMU would give other
    last bits under 3.10/3.11 than under 3.12/3.13. This is what ``sum()`` did before 3.12.
    """
    result = 0.0
    for value in values:
        result += value
    return result


def dot(a, b):
    """``a' b``, added left to right as :func:`total` adds (one loop: no list of the products)."""
    result = 0.0
    for x, y in zip(a, b):
        result += x * y
    return result


def matmul(a, b):
    bt = list(zip(*b))
    return [[dot(row, col) for col in bt] for row in a]


def solve(a, b):
    """``a^-1 b`` for a square ``a`` (Gauss-Jordan with partial pivoting); ``b`` a matrix."""
    n = len(a)
    m = [list(ra) + list(rb) for ra, rb in zip(a, b)]
    for k in range(n):
        pivot = max(range(k, n), key=lambda i: abs(m[i][k]))
        if m[pivot][k] == 0.0:
            raise ZeroDivisionError("singular matrix")
        m[k], m[pivot] = m[pivot], m[k]
        inv = 1.0 / m[k][k]
        m[k] = [x * inv for x in m[k]]
        for i in range(n):
            if i != k and m[i][k] != 0.0:
                f = m[i][k]
                m[i] = [x - f * y for x, y in zip(m[i], m[k])]
    return [row[n:] for row in m]


def norm1(a):
    """The largest absolute column sum."""
    return max(total([abs(row[j]) for row in a]) for j in range(len(a[0])))


def expm(a):
    """The matrix exponential: scaling and squaring with a Taylor series of 20 terms (||a|| <= 1/2 after scaling)."""
    squarings = max(0, math.ceil(math.log2(norm1(a) / 0.5))) if norm1(a) > 0.5 else 0
    a = scaled(a, 0.5 ** squarings)
    n = len(a)
    result, term = identity(n), identity(n)
    for k in range(1, 21):
        term = scaled(matmul(term, a), 1.0 / k)
        result = add(result, term)
    for _ in range(squarings):
        result = matmul(result, result)
    return result


def zoh(a, b, h):
    """Zero-order-hold discretisation ``(Ad, Bd)`` of ``x' = a x + b u`` for the step ``h``.

    Notes
    -----
    ``expm([[a, b], [0, 0]] h) = [[Ad, Bd], [0, I]]``.
    """
    n, m = len(a), len(b[0])
    aug = zeros(n + m, n + m)
    for i in range(n):
        aug[i][:n] = [h * x for x in a[i]]
        aug[i][n:] = [h * x for x in b[i]]
    e = expm(aug)
    return [row[:n] for row in e[:n]], [row[n:] for row in e[:n]]


def dare(a, b, q, r, tol=1e-13, max_iterations=100):
    """The stabilising solution ``P`` of the discrete algebraic Riccati equation.

    ``P = a'Pa - a'Pb (r + b'Pb)^-1 b'Pa + q``, by the structure-preserving
    doubling algorithm (quadratic convergence; Chu, Fan, Lin, Wang, "Structure-preserving
    algorithms for periodic discrete-time algebraic Riccati equations", Int. J. Control 77, 2004):
    ``A <- A (I + G H)^-1 A``, ``G <- G + A (I + G H)^-1 G A'``, ``H <- H + A' H (I + G H)^-1 A``
    from ``A = a``, ``G = b r^-1 b'``, ``H = q``; ``H`` converges to ``P``.

    Raises
    ------
    ArithmeticError
        When the iteration does not converge (the pair is not stabilisable or detectable).
    """
    n = len(a)
    ak, gk, hk = a, matmul(b, matmul(solve(r, identity(len(r))), transpose(b))), q
    for _ in range(max_iterations):
        w = add(identity(n), matmul(gk, hk))
        w_a = solve(w, ak)  # (I + G H)^-1 A
        w_g = solve(w, gk)  # (I + G H)^-1 G
        h_next = add(hk, matmul(transpose(ak), matmul(hk, w_a)))
        g_next = add(gk, matmul(ak, matmul(w_g, transpose(ak))))
        ak = matmul(ak, w_a)
        change = norm1(add(h_next, hk, -1.0))
        hk, gk = h_next, g_next
        if change <= tol * max(1.0, norm1(hk)):
            return [[0.5 * (x + y) for x, y in zip(row, col)] for row, col in zip(hk, transpose(hk))]
    raise ArithmeticError("the Riccati iteration did not converge: is the system stabilisable?")
