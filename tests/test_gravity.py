"""WGS84 normal gravity (:func:`calib.conventions.normal_gravity`) and the unit g.

Checked three ways, none of them the formula under test: the published equator and pole values
(NIMA TR8350.2 table 3.3), Somigliana's formula in its other closed form
``γ = (a γe cos²φ + b γp sin²φ) / √(a² cos²φ + b² sin²φ)`` (algebraically equal: agreement to
1e-9 m/s²), and MATLAB's printed check value ``gravitywgs84(5000, 55, 'TaylorSeries')`` =
9.7997 m/s² (4 decimals: agreement to 5e-5). The free-air gradient near the ground is the
textbook −3.086e-6 s⁻² (±0.01e-6 over latitude).
"""

import numpy as np
import pytest

from calib.conventions import (
    STANDARD_GRAVITY,
    WGS84_A,
    WGS84_F,
    WGS84_GAMMA_E,
    WGS84_GAMMA_P,
    normal_gravity,
)


def _somigliana_other_form(lat_deg: float) -> float:
    a = WGS84_A
    b = a * (1 - WGS84_F)
    c2, s2 = np.cos(np.radians(lat_deg)) ** 2, np.sin(np.radians(lat_deg)) ** 2
    return (a * WGS84_GAMMA_E * c2 + b * WGS84_GAMMA_P * s2) / np.sqrt(a**2 * c2 + b**2 * s2)


def test_published_values_on_the_ellipsoid():
    assert normal_gravity(0.0) == pytest.approx(9.7803253359, abs=1e-9)
    assert normal_gravity(90.0) == pytest.approx(9.8321849378, abs=1e-9)
    assert normal_gravity(-90.0) == normal_gravity(90.0)


@pytest.mark.parametrize("lat", [-89.0, -45.0, -12.5, 0.0, 23.4, 45.0, 55.0, 71.0, 89.9])
def test_agrees_with_the_other_closed_form(lat):
    assert normal_gravity(lat) == pytest.approx(_somigliana_other_form(lat), abs=1e-9)


def test_matlab_check_value_with_height():
    assert abs(normal_gravity(55.0, 5000.0) - 9.7997) <= 5e-5


@pytest.mark.parametrize("lat", [0.0, 45.0, 90.0])
def test_free_air_gradient(lat):
    slope = (normal_gravity(lat, 10.0) - normal_gravity(lat, -10.0)) / 20.0
    assert slope == pytest.approx(-3.086e-6, abs=0.01e-6)


@pytest.mark.parametrize("lat, h", [(91.0, 0.0), (np.nan, 0.0), (45.0, np.inf),
                                    (45.0, 2e5), (-90.5, 0.0)])
def test_out_of_range_is_refused(lat, h):
    with pytest.raises(ValueError, match="latitude|height"):
        normal_gravity(lat, h)


def test_the_unit_g_is_standard_gravity():
    assert STANDARD_GRAVITY == 9.80665
