"""Every `units` of a study file means the variable's quantity in each unit library that
reads it: cf_units (UDUNITS-2, what CF tools and compliance-checker use), pint, and pint
with cf_xarray's CF syntax. A library may reject a string; it must never read another
quantity without a word. UDUNITS reads the Hertz stiffness written as `N m-1.5` as
`0.5 kg s-2` and has no spelling of N m^(-3/2) at all, so the file states the stiffness K
as the force at 1 m of deflection, in `N`. The quantity of each variable is in
cf_quantities.py.

Environment: STUDYRUN_SMOKE_FILE (the result of `studyrun studies/smoke.yaml`); unset:
skip the file tests. STUDYRUN_MERGED_FILE and STUDYRUN_ACCURACY_FILE (`studyrun
accuracy studies/accuracy_smoke.yaml`), if set, are checked too.
"""

import os

import h5py
import pytest

from cf_quantities import (
    pint_registries,
    quantity_of,
    read_cf_units,
    read_pint,
    units_attribute,
)

cf_units = pytest.importorskip("cf_units")
pytest.importorskip("pint")

FILES = ("STUDYRUN_SMOKE_FILE", "STUDYRUN_MERGED_FILE", "STUDYRUN_ACCURACY_FILE")


def file_units(path):
    """{variable: units string} of every dataset in the file."""
    with h5py.File(path, "r") as f:
        return {
            name: units_attribute(obj.attrs["units"]) if "units" in obj.attrs else None
            for name, obj in f.items()
            if isinstance(obj, h5py.Dataset)
        }


@pytest.fixture(scope="module", params=FILES)
def path(request):
    value = os.environ.get(request.param)
    if not value:
        pytest.skip(f"{request.param} is not set")
    assert os.path.isfile(value), f"{request.param}={value} does not exist"
    return value


@pytest.fixture(scope="module")
def units(path):
    return file_units(path)


def test_every_variable_has_units_and_a_known_quantity(units):
    missing = sorted(name for name, u in units.items() if u is None)
    assert not missing, f"no units attribute: {missing}"
    unknown = sorted(name for name in units if quantity_of(name) is None)
    assert not unknown, f"add these variables to cf_quantities.py: {unknown}"


def test_cf_units_never_reads_another_quantity(units):
    wrong = {}
    for name, u in units.items():
        verdict, read = read_cf_units(u, quantity_of(name))
        if verdict == "wrong":
            wrong[name] = read
    assert not wrong, f"cf_units reads a wrong quantity: {wrong}"


def test_cf_units_reads_every_unit(units):
    """What compliance-checker needs: UDUNITS knows every unit of the file."""
    rejected = {}
    for name, u in units.items():
        verdict, read = read_cf_units(u, quantity_of(name))
        if verdict != "correct":
            rejected[name] = read
    assert not rejected, f"cf_units does not read: {rejected}"


DEFAULT_STIFFNESS = 9.57e9
"""`bearing.stiffness` when a grid leaves it out (docs/model.md §2), in N/m^(3/2)."""


def test_the_stiffness_is_k_as_the_force_at_one_metre(path, units):
    """The smoke study leaves K at its default: the file's number is K, its unit N."""
    import pint

    with h5py.File(path, "r") as f:
        values = f["stiffness"][:]
    assert units["stiffness"] == "N"
    reg = pint.UnitRegistry()
    at_1m = (reg.Quantity(DEFAULT_STIFFNESS, "N/m**1.5") * reg.Quantity(1.0, "m") ** 1.5).to("N")
    assert (values == at_1m.magnitude).all(), values


@pytest.mark.parametrize("registry", sorted(pint_registries()))
def test_pint_never_reads_another_quantity(units, registry):
    reg = pint_registries()[registry]
    wrong = {}
    for name, u in units.items():
        verdict, read = read_pint(u, quantity_of(name), reg)
        if verdict == "wrong":
            wrong[name] = read
    assert not wrong, f"{registry} reads a wrong quantity: {wrong}"


def test_pint_with_cf_syntax_reads_every_unit(units):
    """cf_xarray's registry (pint + UDUNITS syntax) reads every unit, the stiffness too;
    a time coordinate in `s since ...` is left to xarray's time decoding."""
    reg = pint_registries().get("cf_xarray-pint")
    if reg is None:
        pytest.skip("cf_xarray is not installed")
    rejected = {}
    for name, u in units.items():
        if " since " in u:
            continue
        verdict, read = read_pint(u, quantity_of(name), reg)
        if verdict == "rejected":
            rejected[name] = read
    assert not rejected, f"cf_xarray-pint rejects: {rejected}"


# ------------------------------------------------------------ the checks themselves, no file


@pytest.mark.parametrize(
    "units, read_as",
    [
        ("N m-1.5", "0.5 kg.s-2"),  # what studyrun wrote: m-1 times .5
        ("N m-3/2", "0.5 m-2.kg.s-2"),  # m-3 divided by 2
        ("kg m-1/2 s-2", "0.5 m-1.kg.s-2"),
        ("N/m^1.5", "5 kg.s-2"),  # m^1 times 5
        ("N m^-1.5", "5 kg.s-2"),
    ],
)
def test_udunits_has_no_fractional_exponents(units, read_as):
    """Every spelling of N m^(-3/2) that UDUNITS accepts means something else; pint
    (plain and with CF syntax) reads the quantity right."""
    assert str(cf_units.Unit(units).definition) == read_as
    assert read_cf_units(units, "hertz_stiffness")[0] == "wrong"
    assert read_pint("N m**-1.5", "hertz_stiffness", pint_registries()["pint"])[0] == "correct"


@pytest.mark.parametrize(
    "units, quantity",
    [
        ("rpm", "crank_speed"),  # UDUNITS and pint: 2 pi / 60 rad/s
        ("m s-2", "acceleration"),
        ("N m", "moment"),
        ("N s m-1", "damping"),
        ("kg m2", "inertia"),
        ("Hz", "frequency"),
        ("1", "dimensionless"),
        ("s since 2000-01-01", "time"),
    ],
)
def test_udunits_reads_the_other_units_correctly(units, quantity):
    assert read_cf_units(units, quantity)[0] == "correct"
    cf_pint = pint_registries().get("cf_xarray-pint")
    if cf_pint is not None and " since " not in units:
        assert read_pint(units, quantity, cf_pint)[0] == "correct"


def test_the_checks_catch_a_wrong_dimension():
    assert read_cf_units("m", "force")[0] == "wrong"
    assert read_cf_units("mm", "length")[0] == "wrong"  # right dimension, wrong factor
    assert read_cf_units("rev/min", "crank_speed")[0] == "rejected"
    for reg in pint_registries().values():
        assert read_pint("m", "force", reg)[0] == "wrong"
        assert read_pint("mm", "length", reg)[0] == "wrong"
