"""Conformance with MATLAB: every system in ../shared/conformance against MATLAB's own evalfis.

Each ``NAME.fis`` there comes with ``NAME.matlab.fld``: a header line naming the inputs then
the outputs, and one row per sample holding the inputs and what MATLAB's ``evalfis``
returned (see the folder's README). fuzzcore must agree within 1e-9 of each output's range
on every row (an implementation of MATLAB's algorithm gets about 1e-13). The data is read in
place and never copied into the repository; without the folder these tests skip.
"""
import numpy as np
import pytest

from conftest import CONFORMANCE_DIR
from fuzzcore import fis_format, yaml_format

pytestmark = pytest.mark.conformance

#: largest tolerated |fuzzcore - MATLAB|, as a fraction of the output's range
TOLERANCE = 1e-9

if CONFORMANCE_DIR.is_dir():
    SYSTEMS = [pytest.param(path, id=f"{path.parent.name}/{path.stem}")
               for path in sorted(CONFORMANCE_DIR.glob("*/*.fis"))]
else:
    SYSTEMS = [pytest.param(None, id="no-data", marks=pytest.mark.skip(
        reason=f"MATLAB conformance data not found at {CONFORMANCE_DIR} (it is not part of the repository)"))]


def _reference(path):
    """(column names, table) of the MATLAB outputs beside ``path``."""
    table_path = path.with_name(path.stem + ".matlab.fld")
    with table_path.open() as f:
        names = f.readline().split()
    table = np.loadtxt(table_path, skiprows=1, ndmin=2)
    assert table.shape[1] == len(names), f"{table_path}: {len(names)} names but {table.shape[1]} columns"
    return names, table


def test_the_data_is_all_there():
    if not CONFORMANCE_DIR.is_dir():
        pytest.skip(f"MATLAB conformance data not found at {CONFORMANCE_DIR}")
    assert len(SYSTEMS) >= 22  # the README's 8 Mamdani and 14 Sugeno systems
    for param in SYSTEMS:
        path = param.values[0]
        assert path.with_name(path.stem + ".matlab.fld").is_file(), f"{path}: no MATLAB table beside it"


@pytest.mark.parametrize("path", SYSTEMS)
def test_matches_matlab_evalfis(path):
    system = fis_format.read(path)
    names, table = _reference(path)
    assert names == list(system.input_names + system.output_names), "the table's columns are not the system's"
    n_in = len(system.inputs)
    got = system.evaluate(table[:, :n_in])
    for o, var in enumerate(system.outputs):
        want = table[:, n_in + o]
        assert np.isfinite(want).all(), f"{var.name}: MATLAB's table has non-finite values"
        error = np.abs(got[:, o] - want) / (var.range[1] - var.range[0])
        worst = int(np.argmax(error))
        assert error[worst] <= TOLERANCE, (
            f"{system.name}.{var.name}: row {worst + 1} inputs {table[worst, :n_in].tolist()}: fuzzcore "
            f"{got[worst, o]!r}, MATLAB {want[worst]!r} ({error[worst]:.3g} of the range)")


@pytest.mark.parametrize("path", SYSTEMS)
def test_fis_round_trip(path):
    system = fis_format.read(path)
    text = fis_format.dumps(system)
    back = fis_format.loads(text)
    assert back == system
    assert fis_format.dumps(back) == text
    _, table = _reference(path)
    X = table[:, :len(system.inputs)]
    np.testing.assert_array_equal(back.evaluate(X), system.evaluate(X))


@pytest.mark.parametrize("path", SYSTEMS)
def test_yaml_round_trip_keeps_every_number(path):
    system = fis_format.read(path)
    back = yaml_format.loads(yaml_format.dumps(system))
    assert back == system
    assert fis_format.dumps(back) == fis_format.dumps(system)
