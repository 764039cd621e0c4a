"""What each variable of a study file measures, and how unit libraries read its `units`.

Shared by test_units.py and test_cf_compliance.py. A `units` string is honest for a
library when the library either reads it as the variable's quantity (1 unit of the file
converts to the reference unit with the right factor) or rejects it; it is wrong when
the library reads some other quantity without a word, as UDUNITS (cf_units) reads
`N m-1.5` as `0.5 kg s-2`: UDUNITS has no fractional exponents, `.` is its
multiplication and `/` its division, so `m-1.5` is m-1 times 5 and `m-3/2` is m-3 / 2.
That is why a file states the Hertz stiffness K (N m^(-3/2)) as the force at 1 m of
deflection, in N.
"""

import math

# quantity: (cf_units reference, pint reference, what 1 unit of the file is in the
#            reference)
QUANTITIES = {
    "dimensionless": ("1", "dimensionless", 1.0),
    "length": ("m", "m", 1.0),
    "angle": ("rad", "rad", 1.0),
    # crank speed, stored in revolutions per minute: 1 rpm = 2 pi / 60 rad/s
    "crank_speed": ("rad s-1", "rad/s", 2.0 * math.pi / 60.0),
    # Hertz contact stiffness K in F = K delta^(3/2) has a half-integer power of length,
    # which no UDUNITS string expresses: a file holds K (1 m)^(3/2), the force at 1 m of
    # deflection, whose number in N is K's in N/m^(3/2)
    "stiffness_at_1m": ("m kg s-2", "N", 1.0),
    # K itself, kg m^(-1/2) s^-2: for the checks that no UDUNITS spelling means it
    "hertz_stiffness": (None, "N/m**1.5", 1.0),
    "spring_stiffness": ("kg s-2", "N/m", 1.0),
    "damping": ("kg s-1", "kg/s", 1.0),
    "mass": ("kg", "kg", 1.0),
    "inertia": ("kg m2", "kg*m**2", 1.0),
    "time": ("s", "s", 1.0),
    "frequency": ("s-1", "1/s", 1.0),
    "acceleration": ("m s-2", "m/s**2", 1.0),
    "moment": ("m2 kg s-2", "N*m", 1.0),
    "force": ("m kg s-2", "N", 1.0),
}

_BY_QUANTITY = {
    "dimensionless": [
        "case", "reference", "reference_index", "status", "error_message", "location",
        "defect_race", "fault",
        "ball_count", "waviness_number", "inner_waviness_number", "outer_waviness_number", "noise_realization",
        "min_loaded_balls", "max_loaded_balls", "steps", "rejected_steps", "rhs_evals",
        "contact_events", "loaded_balls", "speed_profile", "revolution", "replicate",
        "order", "ftf_order", "bpfo_order", "bpfi_order", "bsf_order",
        # accuracy files
        "source_case", "method", "rtol",
    ],
    "length": [
        "clearance", "waviness_amplitude", "inner_waviness_amplitude", "outer_waviness_amplitude",
        "inner_waviness_offset", "outer_waviness_offset", "inner_race_diameter",
        "outer_race_diameter", "crank_length", "rod_length", "eccentricity_x", "eccentricity_y",
        "defect_width", "defect_depth",
    ],
    "angle": ["waviness_phase", "inner_waviness_phase", "outer_waviness_phase", "defect_angle"],
    "crank_speed": ["rpm", "speed_from", "speed_to", "speed_mean", "speed_amplitude"],
    "stiffness_at_1m": ["stiffness"],
    "spring_stiffness": ["k_h"],
    "damping": ["damping", "c_h"],
    "mass": ["crank_mass", "rod_mass", "slider_mass", "m_h"],
    "inertia": ["crank_inertia", "rod_inertia", "slider_inertia"],
    "time": ["time", "wall_time", "stiffness_switch_time", "chatter_time", "speed_over", "horizon", "step"],
    "frequency": ["frequency", "speed_frequency"],
    "acceleration": ["slider_acceleration", "housing_acceleration_x", "housing_acceleration_y"],
    "moment": ["crank_moment"],
    "force": [
        "bearing_force", "bearing_force_x", "bearing_force_y", "crank_ground_force_x",
        "crank_ground_force_y", "crank_rod_force_x", "crank_rod_force_y", "max_bearing_force",
    ],
}
VARIABLES = {name: q for q, names in _BY_QUANTITY.items() for name in names}
"""Variable name -> quantity, for the names that are not derived from another."""

# an accuracy file's errors of channel X, relative to the reference run: dimensionless
_RELATIVE = (
    "reference_metric_uncertainty_", "max_error_", "rms_error_", "metric_error_",
)

# metric_of_X, its value per revolution, spectrum and order spectrum of X and the
# reference run's X have X's quantity
_SUFFIXES = (
    "_per_revolution", "_order_spectrum", "_spectrum", "_rms_deviation", "_peak_deviation",
    "_reference_rms",
)
_PREFIXES = ("reference_",)


def quantity_of(name):
    """The quantity of variable `name`, or None if the table does not know it."""
    if name in VARIABLES:
        return VARIABLES[name]
    if name.startswith(_RELATIVE):
        return "dimensionless"
    for suffix in _SUFFIXES:
        if name.endswith(suffix):
            return quantity_of(name[: -len(suffix)])
    for prefix in _PREFIXES:
        if name.startswith(prefix):
            return quantity_of(name[len(prefix):])
    return None


def _close(got, want):
    return math.isclose(got, want, rel_tol=1e-12, abs_tol=0.0)


def _time_reference_base(units):
    """`s` of `s since 2000-01-01` (a CF time coordinate's units), else None."""
    head, sep, _ = units.partition(" since ")
    return head.strip() if sep else None


def read_cf_units(units, quantity):
    """How cf_units (UDUNITS-2) reads `units` for `quantity`: ("correct" | "rejected" |
    "wrong", what it read)."""
    import cf_units

    cf_ref, _, factor = QUANTITIES[quantity]
    if quantity == "time" and _time_reference_base(units):
        units = _time_reference_base(units)
    try:
        unit = cf_units.Unit(units)
    except ValueError as e:
        return "rejected", str(e)
    if unit.is_unknown() or unit.is_no_unit():
        return "rejected", str(unit)
    read = f"{units!r} as {unit.definition!r}"
    if cf_ref is None:
        return "wrong", f"{read}, though UDUNITS cannot express {quantity}"
    if not unit.is_convertible(cf_units.Unit(cf_ref)):
        return "wrong", f"{read}, not convertible to {cf_ref}"
    got = float(unit.convert(1.0, cf_units.Unit(cf_ref)))
    if not _close(got, factor):
        return "wrong", f"{read}: 1 {units} = {got} {cf_ref}, not {factor}"
    return "correct", read


def read_pint(units, quantity, registry):
    """How a pint `registry` reads `units` for `quantity`, like read_cf_units."""
    import pint

    _, pint_ref, factor = QUANTITIES[quantity]
    try:
        value = registry.Quantity(1.0, units)
    except Exception as e:  # pint raises many types (UndefinedUnitError, TypeError, ...)
        return "rejected", f"{type(e).__name__}: {e}"
    read = f"{units!r} as {value.to_base_units():~}"
    try:
        got = float(value.to(pint_ref).magnitude)
    except pint.DimensionalityError:
        return "wrong", f"{read}, not convertible to {pint_ref}"
    if not _close(got, factor):
        return "wrong", f"{read}: 1 {units} = {got} {pint_ref}, not {factor}"
    return "correct", read


def pint_registries():
    """{name: registry}: plain pint, and cf_xarray's pint registry (pint with CF/UDUNITS
    syntax such as `m s-2`, what `ds.pint.quantify()` users pass) if cf_xarray is
    installed."""
    import pint

    registries = {"pint": pint.UnitRegistry()}
    try:
        from cf_xarray.units import units as cf_registry
    except ImportError:
        pass
    else:
        registries["cf_xarray-pint"] = cf_registry
    return registries


def units_attribute(value):
    """An HDF5 attribute value as str (vlen or fixed-length, scalar or one-element array)."""
    import numpy as np

    if isinstance(value, np.ndarray):
        assert value.size == 1, value
        value = value.reshape(-1)[0]
    if isinstance(value, (bytes, np.bytes_)):
        value = bytes(value).decode("utf-8")
    return str(value)
