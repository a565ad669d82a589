"""randomize ranges proven feasible over their whole box: the interval primitives enclose the
float values of the equations, a narrow infeasible pocket between the old scan points is
found (located independently, from PHYSICS.md's closed forms), feasible ranges construct and
every sub-environment starts, and what cannot be proven is refused as such."""

from __future__ import annotations

import math
import re

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from roller_gym import Scene, feasibility, unstable_rest, validation
from roller_gym.intervals import Interval
from roller_gym.physics import equations
from roller_gym.stabilize import StabilizeTask
from roller_gym.task import unstable_rest_positions
from scipy.optimize import brentq

STABILIZE, HOLD, BALANCE = (roller_gym.TASKS[f"Roller{t}"].env_id()
                            for t in ("Stabilize", "Hold", "Balance"))


# -- the interval primitives enclose the true values -------------------------------------------
def random_box(rng: np.random.Generator, n: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """n random boxes of a scene and a state: (low, high) arrays per quantity, of every sign
    the equations allow (R inside a cylinder or on a drum; φ over several turns)."""
    def span(low, high, relative):
        a = rng.uniform(low, high, n)
        return a, a * (1.0 + rng.uniform(0.0, relative, n))

    r = span(0.05, 0.2, 0.3)
    drum = rng.random(n) < 0.3
    radius = np.where(drum, -rng.uniform(0.3, 3.0, n), r[1] * rng.uniform(1.2, 20.0, n))
    return {
        "m": span(0.1, 5.0, 0.5), "r": r, "R": (radius, radius * rng.uniform(1.0, 1.5, n)),
        "e": span(0.0, 0.05, 1.0), "k": span(0.01, 0.2, 0.5), "g": span(1.0, 20.0, 0.2),
        "c": span(0.0, 0.1, 1.0), "mu": span(0.1, 2.0, 0.5),
        "phi": (lambda a: (a, a + rng.uniform(0.0, 3.0, n)))(rng.uniform(-12.0, 12.0, n)),
        "phi_dot": (lambda a: (a, a + rng.uniform(0.0, 2.0, n)))(rng.uniform(-5.0, 5.0, n)),
        "tau": (lambda a: (a, a + rng.uniform(0.0, 0.5, n)))(rng.uniform(-1.0, 1.0, n)),
    }


def as_intervals(box):
    out = {name: Interval(np.minimum(*ends), np.maximum(*ends)) for name, ends in box.items()}
    out["kappa"] = 1.0 / out.pop("R")
    return out


def points_inside(box, rng, draws):
    """Float points drawn inside each box (draws per box), kappa = 1/R as the Scene has it."""
    out = {}
    for name, (a, b) in box.items():
        low, high = np.minimum(a, b), np.maximum(a, b)
        out[name] = low + (high - low) * rng.random((draws, low.size))
    out["kappa"] = 1.0 / out.pop("R")
    return out


EQUATIONS = {
    "dpotential": lambda x: equations.dpotential(x["phi"], x["m"], x["r"], x["kappa"], x["e"],
                                                 x["g"]),
    "d2potential": lambda x: equations.d2potential(x["phi"], x["m"], x["r"], x["kappa"],
                                                   x["e"], x["g"]),
    "accel": lambda x: equations.accel(x["phi"], x["phi_dot"], x["tau"], x["m"], x["r"],
                                       x["kappa"], x["e"], x["k"], x["g"], x["c"]),
    "normal": lambda x: contact(x)[0],
    "friction": lambda x: contact(x)[1],
    "liftoff margin": lambda x: margins(x)[0],
    "slip margin": lambda x: margins(x)[1],
    "m g r": lambda x: validation.integration_magnitudes(x["m"], x["r"], x["e"], x["k"],
                                                         x["g"])[0],
    "J_min": lambda x: validation.integration_magnitudes(x["m"], x["r"], x["e"], x["k"],
                                                         x["g"])[1],
    "omega_max": lambda x: rates(x)[0],
    "spin": lambda x: rates(x)[1],
    "damping decay": lambda x: rates(x)[2],
    "fastest turns per radian": lambda x: rates(x)[4],
}


def contact(x):
    a = EQUATIONS["accel"](x)
    return equations.contact_forces(x["phi"], x["phi_dot"], a, x["m"], x["r"], x["kappa"],
                                    x["e"], x["g"])


def margins(x):
    normal, friction = contact(x)
    return equations.margins(normal, friction, x["m"], x["g"], x["mu"])


def rates(x):
    _, j_min = validation.integration_magnitudes(x["m"], x["r"], x["e"], x["k"], x["g"])
    return validation.integration_rates(x["m"], x["r"], x["kappa"], x["e"], x["g"], x["c"],
                                        j_min, x["tau"] * x["tau"] + 0.1, 1.0)


@pytest.mark.parametrize("name", list(EQUATIONS))
def test_each_equation_on_intervals_encloses_its_float_values(name):
    rng = np.random.default_rng(sum(map(ord, name)))
    box = random_box(rng, 400)
    with np.errstate(all="ignore"):
        enclosure = EQUATIONS[name](as_intervals(box))
    values = EQUATIONS[name](points_inside(box, rng, 50))  # (50, 400) floats
    assert np.isfinite(values).all()
    low = np.nan_to_num(enclosure.lo, nan=-np.inf)  # NaN: no bound (proves nothing)
    high = np.nan_to_num(enclosure.hi, nan=np.inf)
    inside = (low <= values) & (values <= high)
    assert inside.all(), f"{name}: {np.count_nonzero(~inside)} float values outside"
    assert (np.isfinite(low) & np.isfinite(high)).mean() > 0.9  # and rarely vacuous


def test_the_primitives_enclose_and_find_the_extrema_of_sin_and_cos():
    rng = np.random.default_rng(3)
    a = rng.uniform(-50, 50, 2000)
    b = a + rng.exponential(1.0, 2000)
    c = rng.uniform(0.1, 3, 2000)
    d = c + rng.exponential(1.0, 2000)
    x, y = Interval(a, b), Interval(c, d)
    t = rng.random((30, 1))
    xs, ys = a + (b - a) * t, c + (d - c) * t[::-1]
    for label, result, value in [
        ("+", x + y, xs + ys), ("-", x - y, xs - ys), ("*", x * y, xs * ys),
        ("/", x / y, xs / ys), ("abs", abs(x), np.abs(xs)), ("**2", x ** 2, xs ** 2),
        ("sqrt", np.sqrt(y), np.sqrt(ys)), ("sin", np.sin(x), np.sin(xs)),
        ("cos", np.cos(x), np.cos(xs)), ("2 - x", 2.0 - x, 2.0 - xs),
        ("array * x", np.full(2000, -3.0) * x, -3.0 * xs),
    ]:
        assert ((result.lo <= value) & (value <= result.hi)).all(), label
    # an extremum inside the argument is reached: sin over [π/2 − δ, π/2 + δ] reaches 1
    top = np.sin(Interval(math.pi / 2 - 1e-3, math.pi / 2 + 1e-3))
    assert top.hi == 1.0 and top.lo == pytest.approx(math.cos(1e-3), abs=1e-15)
    bottom = np.cos(Interval(3.0, 3.3))
    assert bottom.lo == -1.0 and bottom.hi == pytest.approx(math.cos(3.3), abs=1e-15)
    # a division by an interval through 0 proves nothing
    q = Interval(1.0) / Interval(-1.0, 1.0)
    assert not (q.lo > -1e300) and not (q.hi < 1e300)


def test_box_params_encloses_kappa_of_each_scene():
    scene = Scene()
    p = feasibility.box_params(scene, {"R": (0.3, 0.9), "m": (0.5, 2.0)})
    for radius in np.linspace(0.3, 0.9, 101):
        assert p.kappa.contains(Scene(R=float(radius)).kappa)
    assert p.m.lo == 0.5 and p.m.hi == 2.0 and p.e.lo == p.e.hi == scene.e


# -- a narrow infeasible pocket between the old scan points ------------------------------------
def start_margin(radius: np.ndarray, scene: Scene, max_torque: float) -> np.ndarray:
    """max over the fallback candidates of min over τ in {−max, 0, +max} of
    min(μN − |F|, N)/(m g), inside a cylinder of radius ``radius``: >= 0 where a fallback
    start rolls. Written from PHYSICS.md's closed forms at rest (φ' = 0), independently of
    roller_gym.physics.equations: J_I = m (k² + r² + e² − 2 r e cos θ),
    J_I φ'' = τ − m g (r sin ψ + e sin φ), N/m = g cos ψ + e φ'' sin θ,
    F/m = g sin ψ + (r − e cos θ) φ''; the candidates ψ = (π/3)(2u − 1), u = ½ and 41
    points in [0, 1], ψ = qφ, q = r/(R − r), θ = φ/(1 − r/R)."""
    m, r, e, k, g, mu = (scene.m, scene.r, scene.e, scene.k, scene.g, scene.mu)
    radius = np.asarray(radius, float)[:, None]
    u = np.concatenate([[0.5], np.linspace(0.0, 1.0, 41)])
    q = r / (radius - r)
    phi = (math.pi / 3.0) * (2.0 * u - 1.0) / q
    psi, theta = q * phi, phi / (1.0 - r / radius)
    inertia = m * (k * k + r * r + e * e - 2.0 * r * e * np.cos(theta))
    worst = np.full(phi.shape, np.inf)
    for tau in (-max_torque, 0.0, max_torque):
        a = (tau - m * g * (r * np.sin(psi) + e * np.sin(phi))) / inertia
        normal = g * np.cos(psi) + e * a * np.sin(theta)
        friction = g * np.sin(psi) + (r - e * np.cos(theta)) * a
        worst = np.minimum(worst, np.minimum(mu * normal - np.abs(friction), normal))
    return worst.max(axis=1) / g


def test_a_narrow_infeasible_pocket_between_scan_points_is_refused():
    """A roller with its mass near the rim (e = 0.9 r, k = 0.3 r) and μ = 0.46 can start
    (some fallback state rolls under ±max_torque) for R in [1.2, 1.5] m except on a pocket
    ~3e-4 m wide, where two candidates' windows of R just fail to overlap; the bottom state
    (φ = 0) needs μ >= 0.51 and fails throughout. The old check (ends and 33 points) passes
    a range with the pocket between two points; the proof refuses it, names a feasible part
    without the pocket, and accepts the parts on either side."""
    scene, max_torque = Scene(e=0.09, k=0.03, mu=0.46), 0.5
    fine = np.linspace(1.2, 1.5, 30_001)  # steps of 1e-5 m
    bad = fine[start_margin(fine, scene, max_torque) < 0]
    assert bad.size and np.all(np.diff(bad) < 2e-5)  # exactly one pocket

    def margin(radius):
        return start_margin([radius], scene, max_torque)[0]

    pocket = (brentq(margin, bad[0] - 1e-5, bad[0], xtol=1e-14),
              brentq(margin, bad[-1], bad[-1] + 1e-5, xtol=1e-14))
    width = pocket[1] - pocket[0]
    assert 0 < width < 1e-3
    spacing = 0.3 / 32  # the range below: 32 gaps between the old 33 points
    center = 0.5 * (pocket[0] + pocket[1])
    low = center - 10.3 * spacing
    high = low + 32 * spacing
    old_points = np.linspace(low, high, 33)
    assert not np.any((old_points >= pocket[0] - width) & (old_points <= pocket[1] + width))
    task = StabilizeTask(max_torque)
    assert all(task.infeasible(scene.replace(R=float(x))) is None for x in old_points)
    assert task.infeasible(scene.replace(R=center)) is not None  # the library agrees
    ranges = {"R": (low, high)}
    for make in (lambda: gym.make(STABILIZE, scene=scene, randomize=ranges),
                 lambda: gym.make_vec(STABILIZE, num_envs=4, scene=scene, randomize=ranges)):
        with pytest.raises(ValueError, match=r"randomize\['R'\].*no start state") as info:
            make()
        part = re.search(r"feasible part of the range: \[([^,]+), ([^\]]+)\]", str(info.value))
        a, b = float(part[1]), float(part[2])
        assert low <= a < b <= high
        assert a >= pocket[1] - 1e-9 or b <= pocket[0] + 1e-9  # the pocket is left out
    for side in ((low, pocket[0] - 1e-4), (pocket[1] + 1e-4, high)):
        feasibility.check_ranges(task, scene, 0.05, {"R": side})  # proven: every start rolls
        # (though with e = 0.09 and mu = 0.46 some start is doomed on its way down)
        with pytest.raises(ValueError, match=r"draws scenes next to .* no torque rolls"):
            gym.make(STABILIZE, scene=scene, randomize={"R": side})


# -- feasible ranges construct, and every sub-environment starts -------------------------------
@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [(STABILIZE, {"randomize": {"m": (0.8, 1.2), "e": (0.03, 0.05)}}),
     (HOLD, {"scene": "floor", "max_torque": 0.8,
             "randomize": {"m": (0.8, 1.2), "e": (0.03, 0.05)}}),
     (BALANCE, {"randomize": {"R": (0.9, 1.5), "m": (0.8, 1.2)}}),
     (BALANCE, {"randomize": {"e": (0.06, 0.08), "mu": (0.8, 1.0)}}),
     (BALANCE, {"scene": "floor", "randomize": {"e": (0.03, 0.05), "k": (0.05, 0.15)}})],
)
def test_feasible_ranges_construct_and_every_sub_environment_starts(env_id, kwargs):
    gym.make(env_id, **kwargs).reset(seed=0)
    vec = gym.make_vec(env_id, num_envs=256, **kwargs)
    obs, info = vec.reset(seed=2)
    assert np.isfinite(obs).all()
    assert (info["liftoff_margin"] > 0).all() and (info["slip_margin"] >= 0).all()
    if env_id == BALANCE:  # the target is each scene's unstable rest position
        for scene, target in zip(vec.unwrapped.scenes, info["target_phi"], strict=True):
            assert abs(target) == pytest.approx(abs(unstable_rest_positions(scene)[0]),
                                                abs=1e-9)
            if math.isinf(scene.R):  # on the floor: the mass center above the axle
                assert abs(target) == pytest.approx(math.pi, abs=1e-12)
    for _ in range(3):
        obs, _, _, _, info = vec.step(np.zeros((256, 1), np.float32))
        assert np.isfinite(obs).all() and not info["nonfinite"].any()


# -- what cannot be proven is refused, naming what was ------------------------------------------
def test_a_range_not_proven_within_the_box_limit_is_refused_naming_the_proven_part(monkeypatch):
    """With one box fewer than the proof needs, the range is refused (never accepted
    unproven), and the proven part it names is accepted."""
    ranges = {"R": (0.7, 1.5)}
    examined = []
    prove = feasibility._boxes_proven
    monkeypatch.setattr(feasibility, "_boxes_proven",
                        lambda *a: examined.extend(a[3]) or prove(*a))
    feasibility._check_ranges_cached.cache_clear()
    try:
        gym.make(BALANCE, randomize=ranges)
        assert len(examined) > 2
        limit = len(examined) - 1
        monkeypatch.setattr(feasibility, "MAX_BOXES", limit)
        feasibility._check_ranges_cached.cache_clear()
        with pytest.raises(ValueError, match=rf"could not be proven within {limit} boxes") as info:
            gym.make(BALANCE, randomize=ranges)
    finally:
        feasibility._check_ranges_cached.cache_clear()
    part = re.search(r"proven: R in \[([^,]+), ([^\]]+)\]", str(info.value))
    assert part, str(info.value)
    monkeypatch.undo()
    low, high = float(part[1]), float(part[2])
    assert 0.7 <= low < high <= 1.5
    gym.make(BALANCE, randomize={"R": (low, high)})  # the named part is indeed proven


def test_a_task_condition_without_a_proof_is_refused():
    class Picky(StabilizeTask):
        def check_scene(self, scene):
            if scene.m > 2.0:
                raise ValueError("too heavy")

    with pytest.raises(ValueError, match=r"no proof.*scene_proven"):
        feasibility.check_ranges(Picky(), Scene(), 0.05, {"m": (0.5, 1.5)})


def test_balance_at_the_top_of_a_drum_and_the_isolated_value_where_it_cannot_be_posed():
    """On top of a drum (R < 0) a mass center near the axle (e < e* = r²/(|R| + r), where
    d²V/dφ²(0) = m g (r²κ/(1 − rκ) + e) changes sign) leaves φ = 0 unstable and the rule
    takes φ_b = 0; above e* an unstable rest position φ_b > 0 appears. At e = e* itself
    there is none (d²V/dφ²(0) = 0), an isolated value no scan finds: a range across it is
    refused as not proven, and the proven part ends below e*."""
    scene = Scene(R=-0.5, e=0.01)
    e_star = scene.r ** 2 / (abs(scene.R) + scene.r)
    vec = gym.make_vec(BALANCE, num_envs=16, scene=scene, randomize={"e": (0.0, 0.5 * e_star)})
    _, info = vec.reset(seed=0)
    assert np.all(np.abs(info["target_phi"]) < 1e-12)  # φ_b = 0, up to the root finder
    with pytest.raises(ValueError, match=r"could not be proven however finely") as error:
        gym.make(BALANCE, scene=scene, randomize={"e": (0.0, 1.8 * e_star)})
    part = re.search(r"proven: e in \[([^,]+), ([^\]]+)\]", str(error.value))
    assert float(part[1]) == 0.0 and 0.99 * e_star < float(part[2]) <= e_star
    gym.make(BALANCE, scene=scene, randomize={"e": (1.2 * e_star, 1.8 * e_star)})


# -- the proof closes on plain domain randomization, and says where it cannot ------------------
def test_plain_domain_randomization_of_four_fields_is_proven_and_every_start_rolls():
    """Four fields around the default scene, m among them over a 4× range (its range was
    counted twice in J_min and the contact forces: refused as not proven); m and g enter the
    start's contact margins only through τ/(m g), so their ends bound them. The proof
    closes; the box is still refused, as its corner m = 2 kg, e = 0.09 m, k = 0.05 m, R =
    0.4 m holds a start doomed on its way down at 0.5 N·m (test_descent), and with R up to
    0.7 m and e up to 0.07 m it constructs."""
    ranges = {"R": (0.4, 1.0), "e": (0.04, 0.09), "k": (0.05, 0.2), "m": (0.5, 2.0)}
    feasibility.check_ranges(StabilizeTask(0.5), roller_gym.preset("paper"), 0.05, ranges)
    with pytest.raises(ValueError, match=r"draws scenes next to .* no torque rolls"):
        gym.make(STABILIZE, randomize=ranges)
    ranges = {**ranges, "R": (0.4, 0.7), "e": (0.04, 0.07)}
    gym.make(STABILIZE, randomize=ranges)
    vec = gym.make_vec(STABILIZE, num_envs=512, randomize=ranges)
    _, info = vec.reset(seed=4)
    assert (info["liftoff_margin"] > 0).all() and (info["slip_margin"] >= 0).all()
    for _ in range(3):
        _, _, _, _, info = vec.step(np.ones((512, 1), np.float32))
        assert not info["nonfinite"].any()


def test_a_range_the_proof_cannot_close_says_it_may_be_feasible_and_names_both_sides(
        monkeypatch):
    """Balance on top of the drum: at r* (d²V/dφ²(0) = 0, 2r² = e(1 + 2r) for R = −0.5 m,
    e = 0.05 m) the unstable rest positions ±φ_b merge into φ = 0, where no interval
    enclosure separates them. The range is refused as possibly feasible, naming the proven
    parts below and above r*, after boxes of SMALLEST_SHARE of the range (splitting them to
    1e-5 took 28 s on r in (0.15, 0.2): the unproven boxes doubled at every depth)."""
    e = 0.05
    r_star = (2 * e + math.sqrt(4 * e * e + 8 * e)) / 4  # 2r² − 2e r − e = 0
    examined = []
    proven = feasibility._boxes_proven

    def counting(task, scene, dt, boxes, ranges):
        examined.append(len(boxes))
        return proven(task, scene, dt, boxes, ranges)

    monkeypatch.setattr(feasibility, "_boxes_proven", counting)
    feasibility._check_ranges_cached.cache_clear()
    with pytest.raises(ValueError, match="may be feasible") as info:
        gym.make(BALANCE, scene="drum", randomize={"r": (0.18, 0.19)})
    assert sum(examined) <= 150, examined  # (measured: 69; 4,000, the most, at 1e-5)
    parts = re.search(r"proven: r in \[([^,]+), ([^\]]+)\] and r in \[([^,]+), ([^\]]+)\]",
                      str(info.value))
    assert parts, str(info.value)
    below, above = (float(parts[1]), float(parts[2])), (float(parts[3]), float(parts[4]))
    assert below[0] == 0.18 and above[1] == 0.19
    assert r_star - 1e-3 < below[1] < r_star < above[0] < r_star + 1e-3


def test_balance_targets_of_randomized_scenes_are_a_batch_computation(monkeypatch):
    """A reset of many Balance sub-environments searches no rest position per scene in
    Python (it did, 7–12 ms each): none at all for fields that cannot move one (m, μ), and
    for r, R and e one compiled call, whose results agree with the search of
    ``physics.equilibria`` (scipy's brentq) on every drawn scene."""
    import roller_gym.rest

    calls = []
    search = roller_gym.rest.equilibria
    monkeypatch.setattr(roller_gym.rest, "equilibria",
                        lambda *a, **k: calls.append(a) or search(*a, **k))
    for ranges in ({"m": (0.8, 1.2), "mu": (0.7, 1.0)}, {"R": (0.9, 1.5), "e": (0.07, 0.084)}):
        vec = gym.make_vec(BALANCE, num_envs=128, randomize=ranges)
        calls.clear()
        _, info = vec.reset(seed=7)
        vec.step(np.zeros((128, 1), np.float32))
        assert len(calls) == 0, ranges
        monkeypatch.setattr(roller_gym.rest, "equilibria", search)
        for scene, target in zip(vec.unwrapped.scenes, info["target_phi"], strict=True):
            assert abs(target) == pytest.approx(abs(unstable_rest_positions(scene)[0]),
                                                abs=1e-12)
        monkeypatch.setattr(roller_gym.rest, "equilibria",
                            lambda *a, **k: calls.append(a) or search(*a, **k))


def test_a_range_over_orders_of_magnitude_is_examined_decade_by_decade():
    """A range whose ends are orders of magnitude apart is split and scanned geometrically:
    Balance with R in (1, 1e6) m is proven (split at arithmetic middles, the proof stalled on
    R in [1, 8.6], a box of 1e-5 of the range, though every part of it is provable), and the
    feasible part named for m in (1, 1e200) kg ends where the roller gets too heavy for the
    torque to stop it in time, in the first of 200 decades (a linear scan named [1, 1]: every
    other point of it was past the bound)."""
    gym.make(BALANCE, randomize={"R": (1.0, 1e6)})
    with pytest.raises(ValueError, match="feasible part of the range") as info:
        gym.make(STABILIZE, randomize={"m": (1.0, 1e200)})
    part = re.search(r"feasible part of the range: \[([^,]+), ([^\]]+)\]", str(info.value))
    assert float(part[1]) == 1.0 and 0.99 * _heaviest() <= float(part[2]) <= 1.03 * _heaviest()


def _heaviest() -> float:
    """The largest m [kg] of Stabilize's default scene whose energy, at rest at the start
    range's edge (ψ = 60°), can be taken out in half the episode (5 s): derived by hand from
    V = m g [(R − r)(1 − cos ψ) + e (1 − cos φ)] and J_min = m (k² + (r − e)²). The torque
    τ takes out at most τ|φ'| a second, and |φ'| <= sqrt(2E/J_min), so the time is at least
    sqrt(2 J_min) (sqrt(E₀) − sqrt(E₁))/τ, E₁ the most energy at success (|φ| <= 0.05 rad,
    |φ'| <= 0.1 rad/s, J_max = m (k² + (r + e)²)); every term goes as m, so the time does."""
    s = Scene()
    r, big_r, e, k, g, tau = s.r, s.R, s.e, s.k, s.g, 0.5
    edge = math.pi / 3 * (big_r - r) / r  # φ at ψ = 60°

    def height(phi: float) -> float:  # V/(m g) [m]
        return (big_r - r) * (1 - math.cos(r * phi / (big_r - r))) + e * (1 - math.cos(phi))

    start = g * height(edge)
    kept = g * height(0.05) + 0.5 * (k * k + (r + e) ** 2) * 0.1**2
    per_kg = math.sqrt(2 * (k * k + (r - e) ** 2)) * (math.sqrt(start) - math.sqrt(kept)) / tau
    return 5.0 / per_kg


def test_a_range_up_to_float64s_top_is_split_without_overflow():
    """A range like R in (0.3, 1e307) is split on a log scale; its middle sqrt(low·high)
    overflowed to inf, and the next box's share (log of its ends' ratio) failed with a math
    domain error, ending construction in a traceback. The middle is now the geometric mean of
    the ends taken one by one, inside the box, and the shares of the two halves add to the
    whole's."""
    from roller_gym.feasibility import _share, _split

    for low, high in ((0.3, 1e307), (1e200, 1e307), (-1e307, -1e200), (1e-300, 1e300)):
        middle = _split(low, high, (low, high))
        assert low < middle < high and math.isfinite(middle)
        halves = _share((low, middle), (low, high)) + _share((middle, high), (low, high))
        assert halves == pytest.approx(1.0, rel=1e-12)


def test_the_swing_ups_pump_time_is_proven_over_a_range_up_to_where_it_fails():
    """The energy success needs and the swing-up's fastest speed scale as m and m⁰, so the
    least pump time of RollerBalanceWeak (max_torque 0.04 N·m) grows as m: a range of m
    holds up to m* = (PUMP_SHARE of the episode) / (the time at m = 1). A range within it is
    proven (each scene drawn from it passes the scalar check too); one past it is refused at
    a scene the scalar check refuses, its feasible part ending just below m*."""
    env_id, torque = roller_gym.TASKS["RollerBalanceWeak"].env_id(), 0.04
    env = gym.make(env_id, max_torque=torque).unwrapped
    task, scene, dt = env.task, env.scene, env.config.dt
    limit = task.PUMP_SHARE * task.max_episode_steps * dt
    m_star = limit / task.pump_time(scene)[2] * scene.m
    assert 1.1 < m_star < 1.6  # (the range below straddles it)
    gym.make(env_id, max_torque=torque, randomize={"m": (0.5, 0.98 * m_star)})
    for m in np.random.default_rng(5).uniform(0.5, 0.98 * m_star, 20):
        assert task.infeasible(scene.replace(m=float(m)), dt) is None
    with pytest.raises(ValueError, match=r"at m = 1\.6 max_torque=0\.04 N·m is too weak") as info:
        gym.make(env_id, max_torque=torque, randomize={"m": (0.5, 1.6)})
    assert task.infeasible(scene.replace(m=1.6), dt) is not None
    part = re.search(r"feasible part of the range: \[([^,]+), ([^\]]+)\]", str(info.value))
    assert float(part[1]) == 0.5 and 0.99 * m_star < float(part[2]) <= m_star


@pytest.mark.parametrize("scene", [roller_gym.preset("balance"), roller_gym.preset("floor"),
                                   Scene(R=-0.5, e=0.03)])  # (a drum: φ_b > 0, e > e*)
def test_the_upper_end_of_the_potential_over_a_box_holds_every_scenes_target_energy(scene):
    """Balance's pump-time and damping proofs rest on an upper end of V(φ_b) over a box (the
    sinc has no enclosure at ψ = 0, so it is bounded by its range instead): it is at least
    V(φ_b) of every scene drawn from the box, φ_b found by the scalar rule, and within a
    factor 2 of the largest on boxes up to a tenth wide (a bound as loose as
    m g (2|R − r| + 2e) failed ranges of R)."""
    from roller_gym.balance import potential_enclosure

    rng = np.random.default_rng(11)
    for _ in range(4):
        box = {"m": (0.8, 1.0 + rng.uniform(0, 0.5)), "e": (0.95 * scene.e, scene.e),
               "k": (0.09, 0.1 + rng.uniform(0, 0.03))}
        if math.isfinite(scene.R):
            box["R"] = tuple(sorted((scene.R, scene.R * (1.0 + rng.uniform(0.01, 0.1)))))
        p = feasibility.box_params(scene, box)
        middle = scene.replace(**{n: 0.5 * (a + b) for n, (a, b) in box.items()})
        with np.errstate(all="ignore"):
            phi = unstable_rest.unstable_rest_enclosure(p, [middle])
            upper = max(float(np.max(potential_enclosure(p, phi).hi)), 0.0)
        energies = []
        for _ in range(30):
            drawn = scene.replace(**{n: float(rng.uniform(a, b)) for n, (a, b) in box.items()})
            phi_b = abs(unstable_rest_positions(drawn)[0])
            assert phi.lo <= phi_b <= phi.hi
            energies.append(float(roller_gym.physics.energy(drawn, phi_b, 0.0)))
        assert max(energies) <= upper <= 2.0 * max(energies)


def test_balance_refuses_a_swing_up_that_cannot_roll_and_proves_ranges_that_can():
    """RollerBalance took e from 0.09 to 0.2 m at R = 1 m (and randomize e in (0.08, 0.2) as
    proven), where the swing that reaches φ_b slips on its way up under every torque within
    the limit (the informed swing-up slipped in every episode). Here the least over the
    swing of the best margin, min(N/(m g), (μN − |F|)/(m g)) at the best of 81 torques in
    ±max_torque, is computed independently of the check's exact interval of torques: it is
    negative where the scene is refused, positive where it is taken; a range across the
    limit is refused naming e, one below it is proven."""
    from roller_gym.balance import BalanceTask
    from roller_gym.physics import energy

    task = BalanceTask()

    def best_margin(scene):
        phi_b = abs(unstable_rest_positions(scene)[0])
        m, r, kappa, e, k, g, c = scene.params
        phi = np.linspace(0.0, phi_b, 1001)
        level = float(energy(scene, phi_b, 0.0))
        speed = np.sqrt(np.maximum(2.0 * (level - equations.potential(phi, m, r, kappa, e, g))
                                   / equations.inertia(phi, m, r, kappa, e, k), 0.0))
        worst = np.inf
        for phi_dot in (speed, -speed):
            best = np.full(phi.shape, -np.inf)
            for tau in np.linspace(-task.max_torque, task.max_torque, 81):
                acc = equations.accel(phi, phi_dot, tau, m, r, kappa, e, k, g, c)
                normal, friction = equations.contact_forces(phi, phi_dot, acc, m, r, kappa, e, g)
                lift, slip = equations.margins(normal, friction, m, g, scene.mu)
                best = np.maximum(best, np.minimum(lift, slip))
            worst = min(worst, float(best.min()))
        return worst

    for e in (0.09, 0.1, 0.14):
        scene = Scene(R=1.0, e=e)
        assert best_margin(scene) < 0
        with pytest.raises(ValueError, match=r"the swing that reaches the unstable rest position "
                                             r".* cannot roll on its way up"):
            gym.make(BALANCE, scene=scene)
    for e in (0.08, 0.085):
        assert best_margin(Scene(R=1.0, e=e)) > 0
        gym.make(BALANCE, scene=Scene(R=1.0, e=e))
    with pytest.raises(ValueError, match=r"randomize\['e'\]=\(0\.08, 0\.2\) cannot be used: "
                                         r"at e = .* cannot roll on its way up"):
        gym.make(BALANCE, randomize={"e": (0.08, 0.2)})
    gym.make(BALANCE, randomize={"e": (0.07, 0.084)})  # proven
    for e in np.random.default_rng(2).uniform(0.07, 0.084, 10):
        assert best_margin(Scene(R=1.0, e=float(e))) > 0
