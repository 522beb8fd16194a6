"""The estimation-side effect registry (``calib.effects``): one object per catalog name.

Guards the structure asked for by "each effect one small object, registered once": the
registry covers the vocabulary of ``calib.conventions.EFFECTS`` exactly, a second registration
fails, the generic engine and states name no effect, and every estimate uses catalog keys.
"""

import inspect

import numpy as np
import pytest

import calib.effects.base as base_module
import calib.effects.engine as engine
from calib.conventions import EFFECT_NAMES, EFFECTS, G
from calib.effects import (
    CATALOG,
    REGISTRY,
    AxisState,
    Effect,
    Extensions,
    FinalFit,
    Likelihood,
    ModelState,
    RunData,
    effect,
    register,
    stated_variances,
)
from calib.files.course import Ensayo
from calib.gap import analyze_gap
from calib.gap.estimates import Reporter


def test_registry_covers_the_vocabulary_once_in_catalog_order():
    assert tuple(e.name for e in CATALOG) == EFFECT_NAMES
    assert set(REGISTRY) == set(EFFECTS)
    for name in EFFECT_NAMES:
        assert effect(name) is REGISTRY[name]
        assert effect(name).info is EFFECTS[name]
    with pytest.raises(ValueError, match="unknown extension"):
        effect("no_such_effect")


def test_a_second_registration_fails():
    class Again(Effect):
        name = "misalignment"

    with pytest.raises(ValueError, match="registered twice"):
        register(Again)

    class Stranger(Effect):
        name = "not_in_the_vocabulary"

    with pytest.raises(ValueError, match="vocabulary"):
        register(Stranger)


def test_engine_and_states_name_no_effect():
    for module in (engine, base_module):
        code = inspect.getsource(module)
        code = "\n".join(line for line in code.splitlines()
                         if not line.lstrip().startswith(("#", '"', "*")))
        named = [n for n in EFFECT_NAMES if f'"{n}"' in code or f"'{n}'" in code]
        assert not named, (module.__name__, named)


def test_add_remove_round_trip_per_axis_effects():
    st = AxisState(sigma2_stated=0.01)
    values = {"lowpass_lag": 0.05, "saturation": 9.0, "bias_random_walk": 1e-3,
              "noise_level": 0.02}
    for e in CATALOG:
        if e.name in ("tilt_offset", "gravity_mismatch", "quantization"):
            continue
        added = e.add(st, values.get(e.name))
        assert e.present(added) and added.effects() == (e.name,)
        assert e.remove(added) == st


def test_estimates_use_catalog_keys():
    rng = np.random.default_rng(7)
    n = 1200
    t = np.arange(n) / 50.0
    th = 1.2 * np.sin(2 * np.pi * t / 10) + 0.2
    a = np.column_stack([-G * np.sin(th), -G * np.cos(th)])
    y = a * 1.01 + 0.05 + 0.01 * rng.standard_normal((n, 2))
    y[:, 0] += 0.004 * a[:, 0] ** 2
    y[:, 1] += 0.003 * t
    res = analyze_gap(Ensayo(tita=th, datos=y, t=t), [1e-4, 1e-4])
    assert res.named
    for est in res.effects:
        assert set(est.params) <= set(EFFECTS[est.name].keys)
        assert set(est.std) == set(est.params)
    state = res.final.state
    assert isinstance(state, ModelState)
    assert state.effects() == [(e.name, e.axis) for e in res.effects]


def _members(proto) -> list[str]:
    """Public names a protocol declares: its methods and its annotated attributes."""
    return sorted({n for n in vars(proto) if not n.startswith("_")}
                  | set(getattr(proto, "__annotations__", {})))


def test_engine_and_final_fit_implement_the_protocols_the_effects_use():
    """The effects are typed against ``Likelihood`` and ``FinalFit`` (calib.effects.base), not
    against the classes: every member is there, with the protocol's parameter names."""
    rng = np.random.default_rng(3)
    th = np.linspace(-3.0, 3.0, 400)
    y = np.column_stack([-G * np.sin(th), -G * np.cos(th)]) + 0.1 * rng.standard_normal((400, 2))
    ext = Extensions(RunData.build(th, y, G), np.ones(2))
    rep = Reporter(ext, ModelState.nominal([0.01, 0.01]))
    for proto, impl in ((Likelihood, ext), (FinalFit, rep)):
        members = _members(proto)
        assert len(members) >= 7, members
        for name in members:
            assert hasattr(impl, name), (proto.__name__, name)
            want = getattr(proto, name, None)
            if callable(want):
                got = inspect.signature(getattr(type(impl), name)).parameters
                assert list(got) == list(inspect.signature(want).parameters), name


def test_the_stated_noise_has_one_form_and_one_check():
    """σ² is stated once (AxisState.sigma2_stated) and checked once (stated_variances);
    the noise level puts an estimate beside it and removing it leaves the statement."""
    state = ModelState.nominal([0.25, 0.64])
    assert [st.sigma2_stated for st in state.axes] == [0.25, 0.64]
    assert not hasattr(RunData, "sigma2") and "noise_var" not in inspect.signature(
        RunData.build).parameters
    free = state.with_axis(1, effect("noise_level").add(state.axes[1], 0.7))
    assert free.axes[1].sigma2 == 0.7 and free.axes[1].noise_free
    assert free.axes[1].sigma2_stated == 0.64
    assert free.without("noise_level", "y") == state
    np.testing.assert_array_equal(stated_variances(np.diag([0.25, 0.64])), [0.25, 0.64])
    for bad in ([0.25], [0.25, -1.0], [np.nan, 1.0], [[1.0, 2.0, 3.0]]):
        with pytest.raises(ValueError, match="two positive variances"):
            ModelState.nominal(bad)
