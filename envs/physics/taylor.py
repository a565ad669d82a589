"""The Taylor series of a roller's motion at constant torque, to a fixed order.

One expansion gives φ(t0 + h) and φ'(t0 + h) for every h inside the series' radius, and its
last coefficients say how large h may be: the ``"taylor"`` scheme of
:mod:`roller_gym.physics.integrators` chooses each substep's size after expanding, so it never
rejects one, and it evaluates the sines only at the expansion point. Everything else is
products of series.

**The recurrences.** With X[n] and V[n] the coefficients of φ and φ' (φ(t0 + h) = Σ X[n] hⁿ),
X[n+1] = V[n]/(n+1) and V[n+1] = A[n]/(n+1), A the series of φ''. :func:`equations.accel`
writes φ'' = L/D with

* L = (τ − c φ')/m − (e r/s) φ'² sin θ − g (r sin ψ + e sin φ),
* D = k² + (r − e)² + 4 r e sin²(θ/2) = k² + (r − e)² + 2 r e (1 − cos θ),

θ = φ/s and ψ = r κ φ/s. A sine and cosine of a series u = a X follow from u' = a φ':
S[n] = (a/n) Σ_{j=1..n} V[j−1] C[n−j], C[n] = −(a/n) Σ_{j=1..n} V[j−1] S[n−j], for θ (a = 1/s),
ψ (a = r κ/s) and φ (a = 1). Products are convolutions (P = U W: P[n] = Σ_j U[j] W[n−j]), and
A = L/D is A[n] = (L[n] − Σ_{j=1..n} D[j] A[n−j]) / D[0]. The order-0 terms are
:func:`equations.accel_terms`, so A[0] is :func:`equations.accel`'s φ'' bit for bit.

**Why generated.** Compiled loops over rollers run in SIMD lanes only if their bodies are
straight-line code. So :func:`source` writes the recurrences out, every sum a balanced tree
(short dependency chains), into one module per degree of :data:`DEGREES`,
``_taylor_series_<degree>.py``, which numba compiles and caches like any module (each only
where a step first uses that degree). Regenerate them after changing this file:
``python -m roller_gym.physics.taylor`` (the tests check that they are current).

**Which degree.** :func:`degree` chooses it from the tolerance (the rule and what it was
measured on: its docstring).
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["DEGREES", "INPUTS", "ORDER", "degree", "generated", "module_name", "program",
           "source", "write"]

#: The degrees of the polynomials in h that one expansion gives, offered by the ``"taylor"``
#: scheme. Each minus 2 is a power of two, so that the step-size rule's root (1/(degree − 2),
#: from the last two terms) is a chain of square roots, which compiled loops vectorize.
DEGREES = (10, 18)
#: The default tolerance's degree (and the largest offered).
ORDER = 18
#: The loosest tolerance at which the default degree is still taken: from it down, ORDER;
#: above it, the lower degree (see :func:`degree`).
LOWER_DEGREE_ABOVE = 0.1


def degree(tolerance: float) -> int:
    """The degree a step at ``tolerance`` (the state error allowed per control step, φ in rad,
    φ' in rad/s) expands to: 10 above :data:`LOWER_DEGREE_ABOVE`, else 18.

    A degree-p expansion costs about p² operations, and a tolerance needs about −ln(tol)/2 + 1
    terms (Jorba and Zou 2005; heyoka takes ⌈−ln(tol)/2 + 1⌉): 11 at 1e-8. But where the
    control step (0.05 s) bounds degree 18's substeps, a lower degree pays for its cheaper
    expansion with more substeps, and where the series' radius bounds them (a stiff scene)
    with many more. Measured (``python -m roller_gym.bench.degrees``; ``docs/MAINTAINERS.md``:
    one core, 1,024 rollers from random states, the degrees alternated in one process),
    degree 10 is the cheaper at the same tolerance on ``paper`` above 1e-5 (1.05× at 3e-5,
    1.4× at 1e-2) but on ``rim_mass`` only above 0.1 (1.6× the cost at 1e-4). A rule of the
    tolerance alone must hold on both, so that loosening the tolerance never makes a step
    costlier: it takes degree 10 only above 0.1, where it is the cheaper on both; degree 6 was
    nowhere the cheapest.
    """
    return DEGREES[0] if tolerance > LOWER_DEGREE_ABOVE else ORDER


def module_name(order: int) -> str:
    """The generated module of degree ``order``, as imported."""
    return f"roller_gym.physics._taylor_series_{order}"


def generated(order: int) -> Path:
    """The file of :func:`module_name`."""
    return Path(__file__).with_name(f"_taylor_series_{order}.py")


def _tree(terms: list[str]) -> str:
    """A sum of ``terms`` as a balanced tree of additions."""
    if len(terms) == 1:
        return terms[0]
    mid = (len(terms) + 1) // 2
    return f"({_tree(terms[:mid])} + {_tree(terms[mid:])})"


def _conv(a: str, b: str, n: int) -> str:
    """Coefficient n of the product of series a and b."""
    return _tree([f"{a}{j} * {b}{n - j}" for j in range(n + 1)])


def _square(a: str, n: int) -> str:
    """Coefficient n of a², each cross term once, doubled."""
    cross = [f"{a}{j} * {a}{n - j}" for j in range((n + 1) // 2)]
    terms = [f"2.0 * {_tree(cross)}"] if cross else []
    if n % 2 == 0:
        terms.append(f"{a}{n // 2} * {a}{n // 2}")
    return _tree(terms)


#: The arguments of ``recurrences``: the state and the scene's numbers the recurrences read,
#: then the order-0 terms of :func:`equations.accel_terms` (L, D and the sines and cosines of
#: θ, ψ and φ) at the expansion point.
INPUTS = ("phi", "phi_dot", "m", "r", "kappa", "e", "g", "c",
          "L0", "D0", "ST0", "CT0", "SQ0", "CQ0", "SF0")


def program(order: int = ORDER) -> list[tuple[str, str]]:
    """The recurrences as assignments (name, expression) in order, from :data:`INPUTS` to
    X[0..order] and V[0..order]: written out as Python by :func:`source`, and as machine code
    by :mod:`roller_gym.physics.taylor_ir`, operation for operation."""
    steps = [("CF0", "CT0 * CQ0 + ST0 * SQ0"), ("X0", "phi"), ("V0", "phi_dot"),
             ("A0", "L0 / D0"), ("s", "1.0 - r * kappa"), ("inv_d0", "1.0 / D0"),
             ("inv_m", "1.0 / m"), ("ers", "e * r / s"), ("two_re", "2.0 * r * e"),
             ("a_t", "1.0 / s"), ("a_q", "r * kappa / s"), ("W0", "V0 * V0")]
    add = steps.append
    for n in range(1, order + 1):
        add((f"X{n}", f"V{n - 1} * {1.0 / n!r}"))
        add((f"V{n}", f"A{n - 1} * {1.0 / n!r}"))
        if n == order:
            break
        # the sines and cosines of θ (T), ψ (Q) and φ (F)
        for sin, cos, rate in (("ST", "CT", "a_t"), ("SQ", "CQ", "a_q"), ("SF", "CF", "1.0")):
            with_cos = _tree([f"V{j - 1} * {cos}{n - j}" for j in range(1, n + 1)])
            with_sin = _tree([f"V{j - 1} * {sin}{n - j}" for j in range(1, n + 1)])
            add((f"{sin}{n}", f"{rate} * {1.0 / n!r} * {with_cos}"))
            if n < order - 1 or cos == "CT":  # the last order needs only cos θ (in D)
                add((f"{cos}{n}", f"-{rate} * {1.0 / n!r} * {with_sin}"))
        add((f"W{n}", _square("V", n)))
        add((f"L{n}", f"-c * V{n} * inv_m - ers * {_conv('W', 'ST', n)} "
                      f"- g * (r * SQ{n} + e * SF{n})"))
        add((f"D{n}", f"-two_re * CT{n}"))
        add((f"A{n}", f"(L{n} - {_tree([f'D{j} * A{n - j}' for j in range(1, n + 1)])}) "
                      "* inv_d0"))
    return steps


def source(order: int = ORDER) -> str:
    """The module ``_taylor_series_<order>.py``: ``coefficients(φ, φ', τ, m, r, κ, e, k, g,
    c)``, returning (X[0..order], V[0..order], (sin θ, cos θ, sin ψ, cos ψ) at the expansion
    point), ``recurrences`` (:func:`program` as Python; compiled, its machine code is
    emitted directly, :mod:`roller_gym.physics.taylor_ir`), ``value(P, h)``, a
    polynomial's value at h, and the step-size rule's ``root(x)``, x^(1/(order − 2)), and
    ``power(h)``, h^(order − 2)."""
    halvings = (order - 2).bit_length() - 1
    if order < 4 or 2**halvings != order - 2:
        raise ValueError(f"order={order}: order − 2 must be a power of two, at least 2")
    inputs = ", ".join(INPUTS)
    lines = [
        f'"""Generated by ``python -m roller_gym.physics.taylor`` (order {order}): do not edit.',
        "",
        "The recurrences are explained in :mod:`roller_gym.physics.taylor`.",
        '"""',
        "",
        "import math",
        "",
        "import numba",
        "from roller_gym.physics import equations as eq",
        "from roller_gym.physics import taylor_ir",
        "",
        f"ORDER = {order}",
        "",
        "# Compiled once; LLVM inlines them where they are called (typing this much code again",
        "# at every call site, as numba's own inlining would, takes a minute).",
        '_jit = numba.njit(cache=True, nogil=True, error_model="numpy", forceinline=True)',
        "",
        "",
        f"def recurrences({inputs}):",
        '    """The Taylor coefficients (X, V) of φ and φ\' and the angles (sin θ, cos θ, sin ψ,',
        "    cos ψ), from the state, the scene's numbers and the order-0 terms (compiled code",
        '    runs the same operations, emitted by taylor_ir)."""',
    ]
    lines += [f"    {name} = {expr}" for name, expr in program(order)]
    xs = ", ".join(f"X{n}" for n in range(order + 1))
    vs = ", ".join(f"V{n}" for n in range(order + 1))
    lines += [
        f"    return ({xs}), ({vs}), (ST0, CT0, SQ0, CQ0)",
        "",
        "",
        "taylor_ir.compile_as_emitted(recurrences, ORDER)",
        "",
        "",
        "@_jit",
        "def coefficients(phi, phi_dot, tau, m, r, kappa, e, k, g, c):",
        '    """(X, V, angles): the Taylor coefficients of φ [rad] and φ\' [rad/s] at this',
        '    state, in powers of the time [s], and its (sin θ, cos θ, sin ψ, cos ψ)."""',
        "    L0, D0, ST0, CT0, SQ0, CQ0, SF0 = eq.accel_terms(phi, phi_dot, tau, m, r, kappa, e,",
        "                                                     k, g, c)",
        f"    return recurrences({inputs})",
        "",
        "",
        "@_jit",
        "def value(P, h):",
        '    """Σ P[n] hⁿ, by Horner\'s rule."""',
    ]
    horner = f"P[{order}]"
    for n in range(order - 1, -1, -1):
        horner = f"({horner}) * h + P[{n}]"
    lines.append(f"    return {horner}")
    root = "x"
    for _ in range(halvings):
        root = f"math.sqrt({root})"
    lines += [
        "",
        "",
        "@_jit",
        "def root(x):",
        f'    """x^(1/{order - 2}), as {halvings} square roots (which vectorize; a power does'
        ' not)."""',
        f"    return {root}",
        "",
        "",
        "@_jit",
        "def power(h):",
        f'    """h^{order - 2}, by {halvings} squarings."""',
        "    h1 = h",
    ]
    lines += [f"    h{2**(i + 1)} = h{2**i} * h{2**i}" for i in range(halvings)]
    lines.append(f"    return h{order - 2}")
    return "\n".join(lines) + "\n"


def write() -> None:
    """Write :func:`source` of every degree of :data:`DEGREES` to :func:`generated`."""
    for order in DEGREES:
        generated(order).write_text(source(order))
        print(f"wrote {generated(order)}")


if __name__ == "__main__":
    write()
