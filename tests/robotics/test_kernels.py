"""The generated kernels (the default path) against the NumPy reference implementations.

Every model, on a tilted base with an offset tool and a payload, for one configuration,
a small batch (the float loop) and a large one (the vectorised path, across chunks)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from ejsrl.robotics import Robot, _kernels
from ejsrl.robotics.transforms import rpy2tr, transl

from testkit.robotics import ALL_MODELS, random_q, with_base_tool

TOL = dict(rtol=1e-10, atol=1e-10)


def pair(name: str, dressed: bool) -> tuple[Robot, Robot]:
    """(fast, reference) copies of one model."""
    robots = []
    for fast in (True, False):
        r = ALL_MODELS[name]()
        if dressed:
            with_base_tool(r)
            r.payload(1.3, [0.01, -0.02, 0.05], [0.002, 0.003, 0.004])
            r.gravity = np.array([0.3, -0.2, -9.7])
        r._fast = fast
        robots.append(r)
    return robots[0], robots[1]


CASES = [(name, dressed) for name in ALL_MODELS for dressed in (False, True)]


@pytest.mark.parametrize("name,dressed", CASES)
@pytest.mark.parametrize("m", [None, 7, 123])
def test_kernels_match_reference(name: str, dressed: bool, m: int | None, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_kernels, "CHUNK", 50)  # 123 configurations: vectorised, in three chunks
    assert _kernels.SMALL_BATCH < 123
    fast, ref = pair(name, dressed)
    rng = np.random.default_rng(5)
    q = random_q(fast, rng, m)
    shape = q.shape
    qd = rng.uniform(-2, 2, shape)
    qdd = rng.uniform(-3, 3, shape)
    tau = rng.uniform(-20, 20, shape)
    for op, args, kw in [
        ("fkine", (q,), {}),
        ("fkine_all", (q,), {}),
        ("jacob0", (q,), {}),
        ("jacobe", (q,), {}),
        ("rne", (q, qd, qdd), {}),
        ("rne", (q, qd, qdd), dict(friction=False, armature=False, gravity=[0.0, 1.0, -3.0])),
        ("rne", (q, None, qdd), {}),
        ("rne", (q, qd), dict(armature=False)),
        ("gravload", (q,), {}),
        ("inertia", (q,), {}),
        ("accel", (q, qd, tau), {}),
    ]:
        got = getattr(fast, op)(*args, **kw)
        want = getattr(ref, op)(*args, **kw)
        assert got.shape == want.shape, op
        np.testing.assert_allclose(got, want, **TOL, err_msg=f"{name} {op} {kw}")


def test_kernels_follow_parameter_edits() -> None:
    fast, ref = pair("puma560", False)
    q = fast.qn
    fast.inertia(q)  # build, then change the arm
    for r in (fast, ref):
        r.links[2].m = 7.0
        r.links[1].a = 0.5
        r.base = transl(0.1, 0.2, 0.3) @ rpy2tr(0.1, 0.2, 0.3)
        r.tool = transl(0.0, 0.0, 0.2)
    for op in ("fkine", "jacob0", "inertia", "gravload"):
        np.testing.assert_allclose(getattr(fast, op)(q), getattr(ref, op)(q), **TOL)
    with pytest.raises(ValueError):
        fast.base[0, 3] = 1.0  # read-only: the kernels would not see an in-place edit


def test_batch_keeps_leading_shape() -> None:
    fast, ref = pair("ur5", True)
    q = random_q(fast, np.random.default_rng(2), 60).reshape(3, 20, 6)
    np.testing.assert_allclose(fast.fkine(q), ref.fkine(q), **TOL)
    assert fast.jacob0(q).shape == (3, 20, 6, 6)


def test_generated_code_drops_vanishing_terms() -> None:
    """On the Puma (alpha in {0, +-90 deg}, identity base and tool) forward kinematics
    needs under 100 arithmetic operations besides the 12 sines and cosines, far fewer
    than six general 4x4 products (about 500)."""
    fast, _ = pair("puma560", False)
    src = fast._kernel(("fkine",)).source
    assert len(re.findall(r" [-+*/] ", src)) < 100
    assert src.count("sin(") + src.count("cos(") == 12


def test_single_configuration_outside_math_domain_gives_nan_like_numpy() -> None:
    fast, ref = pair("puma560", False)
    q = np.array([np.inf, 0.1, 0.2, 0.3, 0.4, 0.5])
    with np.errstate(invalid="ignore"):
        want = ref.fkine(q)
    got = fast.fkine(q)
    assert np.array_equal(np.isnan(got), np.isnan(want)) and np.isnan(got).any()


def test_accel_of_massless_arm_raises_like_numpy() -> None:
    from ejsrl.robotics import RevoluteDH

    for fast in (True, False):
        r = Robot([RevoluteDH(a=1.0), RevoluteDH(a=1.0)])
        r._fast = fast
        with pytest.raises(np.linalg.LinAlgError):
            r.accel([0.1, 0.2], [0.0, 0.0], [1.0, 1.0])
        with pytest.raises(np.linalg.LinAlgError):
            r.accel(np.zeros((60, 2)), np.zeros(2), np.ones(2))


def test_damped_step_matches_numpy_solve() -> None:
    fast, _ = pair("pa10", False)
    rng = np.random.default_rng(3)
    J = rng.normal(size=(6, fast.n))
    e, w, lam = rng.normal(size=6), np.array([1.0, 1.0, 0.5, 1.0, 0.0, 2.0]), 0.05
    got = fast._kernel(("lm_step",)).single(*J.ravel(), *e, *w, lam)
    JtW = J.T * w
    want = np.linalg.solve(JtW @ J + lam * np.eye(fast.n), JtW @ e)
    np.testing.assert_allclose(got, want, **TOL)


@pytest.mark.parametrize("angle", [0.7, 1e-8, np.pi - 1e-9, np.pi])
def test_float_pose_error_matches_numpy(angle: float) -> None:
    from ejsrl.robotics.ik import _pose_error_rows, pose_error
    from ejsrl.robotics.transforms import angvec2tr

    Tg = transl(0.1, 0.2, 0.3) @ rpy2tr(0.3, -0.2, 0.5)
    T = transl(0.0, 0.25, 0.1) @ angvec2tr(angle, [0.3, -0.5, 0.8]) @ Tg
    T[:3, 3] = [0.0, 0.25, 0.1]
    got = _pose_error_rows(Tg[:3].tolist(), tuple(T.ravel().tolist()))
    np.testing.assert_allclose(got, pose_error(Tg, T), rtol=1e-9, atol=1e-9)


def test_robot_pickles_without_its_generated_code() -> None:
    import pickle

    fast, _ = pair("puma560", True)
    q = fast.qn
    T = fast.fkine(q)
    clone = pickle.loads(pickle.dumps(fast))
    np.testing.assert_allclose(clone.fkine(q), T, **TOL)
    assert not clone.tool.flags.writeable
