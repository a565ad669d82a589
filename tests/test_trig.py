"""The branch-free sine and cosine, and the compiled kernels that use them.

* Accuracy against mpmath at 50 digits (an independent reference) and against ``math.sin``.
* The compiled code gives the same bits as the NumPy evaluation of the same source, and
  NumPy's own sin (what Python callers get) within 1 ulp.
* The loops over rollers compile to SIMD code (what the branch-free form is for).
* Every integration kernel, compiled, gives the same bits as the same kernel interpreted by
  Python (numba disabled): a compiler mistake (wrongly inlined code, say) cannot hide.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys

import mpmath
import numba
import numpy as np
import pytest
import roller_gym
from roller_gym.physics import integrators as integ
from roller_gym.physics import preset, trig

mpmath.mp.dps = 50


def _sample(seed: int = 0) -> np.ndarray:
    """Arguments over the range the simulation uses and the reduction's hard cases."""
    rng = np.random.default_rng(seed)
    near_quadrants = np.arange(-2000, 2000) * (math.pi / 2)  # rounded: near multiples of π/2
    return np.concatenate([
        rng.uniform(-4, 4, 3000),
        rng.uniform(-1e3, 1e3, 2000),
        rng.uniform(-trig.EXACT_RANGE, trig.EXACT_RANGE, 2000),
        10.0 ** rng.uniform(-300, -1, 500) * rng.choice([-1, 1], 500),
        near_quadrants,
        np.nextafter(near_quadrants, np.inf),
        [0.0, -0.0, 5e-324, math.pi, -math.pi, 355.0, 103993.0, 1.5707963267948966],
    ])


def _ulps(value: np.ndarray, exact: list) -> np.ndarray:
    """|value − exact| in units of the last place of the exact value (as float64)."""
    ref = np.array([float(v) for v in exact])
    err = np.array([abs(mpmath.mpf(float(a)) - b) for a, b in zip(value, exact, strict=True)],
                   dtype=float)
    return err / np.spacing(np.maximum(np.abs(ref), np.finfo(float).tiny))


# trig._sin and trig._cos evaluate the compiled form with NumPy (the same bits: tested below)
@pytest.mark.parametrize(("ours", "ref", "libm"), [(trig._sin, mpmath.sin, math.sin),
                                                    (trig._cos, mpmath.cos, math.cos)])
def test_within_one_ulp_of_the_exact_value_and_two_of_libm(ours, ref, libm):
    x = _sample()
    got = ours(x)
    exact = [ref(mpmath.mpf(float(v))) for v in x]
    assert _ulps(got, exact).max() <= 1.0
    theirs = np.array([libm(float(v)) for v in x])
    assert (np.abs(got - theirs) <= 2 * np.spacing(np.abs(theirs))).all()


@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")  # as np.sin(inf) warns
def test_outside_the_domain_is_nan_and_beyond_the_exact_range_stays_close():
    bad = np.array([np.inf, -np.inf, np.nan, 2.0 * trig.DOMAIN, -1e300])
    assert np.isnan(trig._sin(bad)).all() and np.isnan(trig._cos(bad)).all()
    x = np.random.default_rng(1).uniform(trig.EXACT_RANGE, 1e12, 200)
    exact = np.array([float(mpmath.sin(mpmath.mpf(float(v)))) for v in x])
    # the documented bound: an absolute error below |x|·2⁻⁵² (the rounding of x itself)
    assert (np.abs(trig._sin(x) - exact) <= np.abs(x) * 2.0**-52).all()


def test_compiled_code_gives_the_bits_of_its_numpy_evaluation_and_libm_within_one_ulp():
    x = _sample(2)

    @numba.njit(error_model="numpy")
    def both(x, s, c, s2, c2):
        for i in range(x.size):
            s[i], c[i] = trig.sin(x[i]), trig.cos(x[i])
            s2[i], c2[i] = trig.sincos(x[i])

    s, c, s2, c2 = (np.empty_like(x) for _ in range(4))
    both(x, s, c, s2, c2)
    assert np.array_equal(s, trig._sin(x)) and np.array_equal(c, trig._cos(x))
    # sincos, one reduction for both: the bits of sin and cos
    assert np.array_equal(s2, s) and np.array_equal(c2, c)
    assert all(np.array_equal(a, b) for a, b in zip(trig.sincos(x), (s, c), strict=True))
    # called from Python on numbers, they are the compiled form too, as NumPy scalars
    for i in range(0, x.size, max(1, x.size // 200)):
        for v in (float(x[i]), x[i], np.array(x[i])):
            got = trig.sin(v), trig.cos(v), *trig.sincos(v)
            assert got == (s[i], c[i], s[i], c[i])
            assert all(type(g) is np.float64 for g in got)


def test_float64_arrays_from_python_get_the_compiled_bits_in_any_layout():
    """From Python, a float64 array goes through the compiled loop: the bits of the NumPy
    evaluation of the branch-free form, for any shape, strides and size; other types are
    NumPy's (complex numbers keep working, for complex-step derivatives)."""
    x = _sample(3)[: 64 * 60].reshape(64, 60)
    for view in (x, x.T, x[::3, 1::2], x[:, :1], x[0, :3]):
        got_s, got_c = trig.sin(view), trig.cos(view)
        assert got_s.shape == view.shape and got_s.dtype == np.float64
        assert np.array_equal(got_s, trig._sin(np.array(view)))
        assert np.array_equal(got_c, trig._cos(np.array(view)))
        pair = trig.sincos(view)
        assert np.array_equal(pair[0], got_s) and np.array_equal(pair[1], got_c)
        assert pair[0].shape == view.shape
    single = x[0, :1].astype(np.float32)
    assert trig.sin(single).dtype == np.float32  # not float64: NumPy's
    z = x[0] + 1e-20j
    assert np.array_equal(trig.sin(z), np.sin(z))
    assert trig.sin(np.empty((0, 3))).shape == (0, 3)


def _exp_sample(seed: int = 4) -> np.ndarray:
    """exp's arguments: the whole range (overflow at 709.78, subnormals below −708.4, 0 below
    −745.1), the range the rewards use, tiny ones and the edges."""
    rng = np.random.default_rng(seed)
    return np.concatenate([
        rng.uniform(-750, 712, 1500), rng.uniform(-30, 3, 1500),
        10.0 ** rng.uniform(-300, 0, 300) * rng.choice([-1, 1], 300),
        [0.0, -0.0, 709.782712893384, 709.7827128933841, -708.3964185322641,
         -745.1332191019411, -745.1332191019412, 1.0, -1.0, 0.5 * math.log(2.0)],
    ])


def _tanh_sample(seed: int = 5) -> np.ndarray:
    """tanh's arguments: both forms (|x| below and above 0.625), tiny and saturated ones."""
    rng = np.random.default_rng(seed)
    return np.concatenate([
        rng.uniform(-25, 25, 1500), rng.uniform(-1, 1, 1500),
        10.0 ** rng.uniform(-300, 0, 300) * rng.choice([-1, 1], 300),
        [0.0, -0.0, 0.625, -0.625, np.nextafter(0.625, 0.0), 19.06, 400.0],
    ])


@pytest.mark.parametrize(("ours", "ref", "sample", "ulps"),
                         [(trig._exp, mpmath.exp, _exp_sample, 1.0),
                          (trig._tanh, mpmath.tanh, _tanh_sample, 2.0)])
def test_exp_and_tanh_within_their_ulps_of_the_exact_value(ours, ref, sample, ulps):
    """The branch-free exp (1 ulp) and tanh (2 ulp: its form 1 − 2/(e^{2|x|} + 1) above
    |x| = 0.625 rounds three times) against mpmath at 50 digits, subnormal and overflowing
    results included; inf and NaN as libm's."""
    x = sample()
    with np.errstate(over="ignore"):
        got = ours(x)
    exact = [ref(mpmath.mpf(float(v))) for v in x]
    rounded = np.array([float(v) for v in exact])
    overflow = np.isinf(rounded)  # beyond float64: the exact value rounds to inf
    assert np.array_equal(got[overflow], rounded[overflow])
    err = np.array([abs(mpmath.mpf(float(a)) - b) for a, b in
                    zip(got[~overflow], np.array(exact, dtype=object)[~overflow], strict=True)],
                   dtype=float)
    # in units of the last place, subnormal ones included (their spacing is 5e-324)
    assert (err <= ulps * np.spacing(np.maximum(np.abs(rounded[~overflow]), 5e-324))).all()
    with np.errstate(all="ignore"):
        special = ours(np.array([np.inf, -np.inf, np.nan]))
    libm = {mpmath.exp: np.exp, mpmath.tanh: np.tanh}[ref]
    assert np.array_equal(special, libm(np.array([np.inf, -np.inf, np.nan])), equal_nan=True)
    assert np.signbit(ours(np.array([-0.0]))) == np.signbit(libm(np.array([-0.0])))


def test_exp_and_tanh_compiled_give_the_bits_of_their_numpy_evaluation():
    """Compiled (a SIMD loop) and evaluated by NumPy, the same source gives the same bits;
    from Python, float64 arrays take the compiled loop and scalars NumPy's own (within 1 ulp
    of libm's exp, 2 of its tanh)."""
    x, t = _exp_sample(6), _tanh_sample(7)
    with np.errstate(over="ignore", invalid="ignore"):
        assert np.array_equal(trig.exp(x), trig._exp(x))
        assert np.array_equal(trig.tanh(t), trig._tanh(t))
    assert trig.exp(0.3) == np.exp(0.3) and trig.tanh(0.3) == np.tanh(0.3)
    for x0 in (-7.25, 0.3, 11.0):
        assert abs(trig.exp(np.full(64, x0))[0] - math.exp(x0)) <= np.spacing(math.exp(x0))
        assert (abs(trig.tanh(np.full(64, x0))[0] - math.tanh(x0))
                <= 2 * np.spacing(abs(math.tanh(x0))))

    @numba.njit(error_model="numpy")
    def both(x, out):
        for i in range(x.size):
            out[i] = trig.exp(x[i]) + trig.tanh(x[i])

    out = np.empty(64)
    both(np.linspace(-3, 3, 64), out)
    assert "vector.body" in both.inspect_llvm(both.signatures[0])


@pytest.mark.parametrize("task_id", roller_gym.ENV_IDS)
def test_the_outcome_of_a_block_of_rollers_runs_in_simd_lanes(task_id):
    """The step's outcome (the task's reward and success, flags, info and observation
    values: exp, tanh and sines included) is computed in one loop that LLVM runs in SIMD
    lanes, for every task's own objective."""
    import gymnasium as gym
    from roller_gym.episode.outcome import SCRATCH_SIZE, _outcome_block

    task = gym.spec(task_id).make().unwrapped.task
    reward, success, k = type(task).reward, type(task).success, task.constants

    @numba.njit(error_model="numpy", nogil=True)
    def block(b, m):
        _outcome_block(reward, success, k, b, m)

    block(np.zeros(SCRATCH_SIZE), 16)
    assert "vector.body" in block.inspect_llvm(block.signatures[0])


@pytest.mark.parametrize("lanes", ["_accel_lanes", "_margin_lanes", "_end_lanes"])
def test_the_loops_over_rollers_run_in_simd_lanes(lanes):
    # compiled afresh (the kernels' cache hides their IR), with the kernels' own options
    fn = numba.njit(error_model="numpy", nogil=True)(getattr(integ, lanes).py_func)
    n = 64
    par = integ.scene_arrays(preset("paper"), n)
    x = np.linspace(-1, 1, n)
    if lanes == "_accel_lanes":
        fn(x, x, x, par, n, np.empty(n))
    elif lanes == "_margin_lanes":
        fn(x, x, x, par, n, np.empty(n), np.empty(n))
    else:
        fn(x, x, x, par, n, np.zeros((6, n)))
    assert "vector.body" in fn.inspect_llvm(fn.signatures[0])


def test_the_accept_loops_of_the_adaptive_kernel_run_in_simd_lanes():
    """The error norms and step-size factors take square roots; in SIMD lanes they are vector
    square roots (LLVM drops a loop to scalar code when its rows need too many overlap
    checks, which is why accepting is split into loops): at least the two of the estimates'
    loop and the two of the step-size factor's (one loop was dropped to scalar code with only
    the estimates' two left vector when the accept loop wrote two more rows)."""
    fn = numba.njit(error_model="numpy", nogil=True)(integ._rk_chunk.py_func)
    io = np.zeros((len(integ.ROWS), 4))
    io[: len(integ.SCENE_FIELDS)] = integ.scene_arrays(preset("paper"), 4)
    sch = integ.SCHEMES["rk8"]
    cfg = integ.Stepper(preset("paper"), integrator="rk8", dt=0.05, tolerance=1e-8)._cfg
    assert dict(zip(integ.CFG_FIELDS, cfg, strict=True))["tol_share"] == sch.tol_share
    fn(io, 0, 4, sch.tableau, cfg)
    assert io[integ._ROW["finite"]].all()
    ir = fn.inspect_llvm(fn.signatures[0])
    assert "llvm.sqrt.v" in ir
    assert len(re.findall(r"call <\d+ x double> @llvm\.sqrt\.v", ir)) >= 4


_INTERPRETED = r"""
import json, os, sys
import numpy as np
from roller_gym.physics import integrators as integ, preset, Scene, trig
if os.environ["NUMBA_DISABLE_JIT"] == "1":  # interpreted, sin and cos are NumPy's: take the
    for name in ("sin", "cos", "sincos", "exp", "tanh"):  # branch-free form the compiled
        def either(x, free=getattr(trig, "_" + name), face=getattr(trig, name)):  # code has
            return free(x) if trig._looped(x) else face(x)  # (intervals: the face's)
        setattr(trig, name, either)
rng = np.random.default_rng(3)
n = 4  # interpreted, a kernel runs about 10,000 times slower: one roller per scene
scenes = [preset("paper"), preset("drum"), preset("floor"), Scene(R=0.21, e=0.09)]
out = {}
# euler and midpoint at looser tolerances: at 1e-8 their predicted substeps (up to 200,000)
# would take minutes interpreted
for method, sub, tol in (("rk8", None, 1e-8), ("rk4", None, 1e-8), ("rk8", 3, 1e-8),
                         ("euler", None, 1e-3), ("midpoint", None, 1e-5)):
    stepper = integ.BatchStepper(n, integrator=method, dt=0.05, tolerance=tol,
                                 substeps=sub)
    for j, sc in enumerate(scenes):
        stepper.set_scenes(sc, j)
    phi, w = rng.uniform(-1.5, 1.5, n), rng.uniform(-4, 4, n)
    for _ in range(2):
        res = stepper.advance(phi, w, rng.uniform(-0.3, 0.3, n))
        phi, w = res.phi.copy(), res.phi_dot.copy()
    out[f"{method}-{sub}"] = [np.asarray(getattr(res, f), dtype=float).tolist()
                              for f in integ.STEP_FIELDS]
# the single environment's step: compiled, one call on packed buffers; interpreted, two calls
import gymnasium as gym
import roller_gym
env = gym.make("roller_gym/RollerHold-v2", tolerance=1e-6)
(obs, info), reward, terminated, rows = env.reset(seed=2), 0.0, False, []
for a in (None, 0.3, -0.8, 0.5):
    if a is not None:
        obs, reward, terminated, _, info = env.step(np.array([a], np.float32))
    rows.append([*obs.tolist(), reward, float(terminated), *map(float, info.values())])
out["single env"] = rows
json.dump(out, sys.stdout)
"""


def _run(disable_jit: bool) -> dict:
    env = dict(os.environ, NUMBA_DISABLE_JIT="1" if disable_jit else "0")
    done = subprocess.run([sys.executable, "-c", _INTERPRETED], env=env, capture_output=True,
                          text=True, check=True, timeout=900)
    return json.loads(done.stdout)


def test_compiled_kernels_give_the_interpreted_bits():
    """The kernels, and a single environment's reset and steps, give the same bits compiled
    and interpreted (NUMBA_DISABLE_JIT, with the branch-free functions the compiled code
    takes)."""
    compiled, interpreted = _run(False), _run(True)
    assert compiled.keys() == interpreted.keys()
    for key in compiled:
        a, b = np.array(compiled[key]), np.array(interpreted[key])
        assert np.array_equal(a, b, equal_nan=True), key
