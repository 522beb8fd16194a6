"""The estimation-side effect registry (``calib.effects``): one object per catalog name.

Guards the structure asked for by "each effect one small object, registered once": the
registry covers the vocabulary of ``calib.conventions.EFFECTS`` exactly, a second registration
fails, the generic engine and states name no effect, and every estimate uses catalog keys.
"""

import inspect

import numpy as np
import pytest

import calib.effects.engine as engine
import calib.effects.state as state_module
from calib.conventions import EFFECT_NAMES, EFFECTS, G
from calib.effects import CATALOG, REGISTRY, AxisState, Effect, ModelState, effect, register
from calib.gap import analyze_gap
from calib.io import Ensayo


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
    for module in (engine, state_module):
        code = inspect.getsource(module)
        code = "\n".join(line for line in code.splitlines()
                         if not line.lstrip().startswith(("#", '"', "*")))
        named = [n for n in EFFECT_NAMES if f'"{n}"' in code or f"'{n}'" in code]
        assert not named, (module.__name__, named)


def test_add_remove_round_trip_per_axis_effects():
    st = AxisState(sigma2=0.01)
    values = {"lowpass_lag": 0.05, "saturation": 9.0, "bias_random_walk": 1e-3,
              "noise_level": 0.02}
    for e in CATALOG:
        if e.name in ("tilt_offset", "gravity_mismatch", "quantization"):
            continue
        added = e.add(st, values.get(e.name))
        assert e.present(added) and added.effects() == (e.name,)
        assert e.remove(added, 0.01) == st


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
