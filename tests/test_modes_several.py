"""``impactbeams modes`` of several contacts (issue 33): the free modes, each contact's phase.

The free modes do not depend on the contacts; each contact's column is its contact phase
closed alone. Checks: beside a second contact, the first one's column and the free modes are
the single contact's output; each column is its contact phase's eigenproblem solved densely.
"""

import json

import numpy as np
import pytest

from impactbeams.cli import main
from impactbeams.contact.active_sets import several_contacts
from impactbeams.contact.spring import recommended_modes
from impactbeams.model import build_free_phase
from impactbeams.params import Params

N = 4
SINGLE = ["--counterpart", "stop", "--contact-stiffness", "1e4", "--clearance", "1e-5"]
CONTACTS = ('[params]\ncounterpart = "stop"\ncontact_stiffness = 1e4\n'
            "[[params.contacts]]\nclearance = 1e-5\n"  # the single contact's
            "[[params.contacts]]\nposition1 = 0.05\nclearance = 1e-3\nstiffness = 1e5\n")


@pytest.fixture()
def two(tmp_path):
    path = tmp_path / "two.toml"
    path.write_text(CONTACTS)
    return path


def printed(capsys, *arguments):
    assert main(["modes", "--n", str(N), *arguments]) == 0
    return capsys.readouterr().out


def test_the_first_contact_s_column_is_the_single_contact_s(capsys, two):
    """The free column and contacts[0]'s are the single contact's numbers, as printed; the
    table names each contact (side and point) and says each is closed alone."""
    single = json.loads(printed(capsys, *SINGLE, "--json"))
    several = json.loads(printed(capsys, "--params", str(two), "--json"))
    assert several["free"] == single["free"]
    assert [c["contact"] for c in several["contacts"]] == [
        "contacts[0] (below, x1 = 0.1 m)", "contacts[1] (below, x1 = 0.05 m)"]
    assert several["contacts"][0]["frequencies"] == single["contact"]
    table = printed(capsys, "--params", str(two)).splitlines()
    single_table = printed(capsys, *SINGLE).splitlines()
    assert table[0].endswith("each contact closed alone:")
    assert table[1:3] == ["  contacts[0] (below, x1 = 0.1 m)",
                          "  contacts[1] (below, x1 = 0.05 m)"]
    assert table[3].split() == ["mode", "beam", "1", "free", "contacts[0]", "contacts[1]"]
    for row, single_row in zip(table[4:], single_table[2:], strict=True):
        assert row.split()[:3] == single_row.split()


def test_each_column_is_the_contact_phase_s_eigenproblem(capsys, two):
    """Each contact's frequencies are the square roots of the eigenvalues of its undamped
    contact phase, diag(omega_n^2) + k_eff b b^T (b its gap's modal weights, k_eff its
    spring in series with the flexibility the modes miss), at the modes that resolve it:
    a dense symmetric eigensolver against the rank-one updates the package uses (1e-10,
    measured 1.3e-13: 12 modes, the largest omega^2 1.4e5 times the first)."""
    several = json.loads(printed(capsys, "--params", str(two), "--json"))
    params = Params.from_toml(two)
    for i, run in enumerate(params.each_contact()):
        n_modes = max(N, recommended_modes(run))
        free = build_free_phase(run, n_modes)
        residual = several_contacts(params, n_modes).residual[i, i]
        k_eff = run.contact_stiffness / (1.0 + run.contact_stiffness * residual)
        stiffness = np.diag(free.frequencies**2) + k_eff * np.outer(free.gap_weights,
                                                                      free.gap_weights)
        np.testing.assert_allclose(several["contacts"][i]["frequencies"],
                                   np.sqrt(np.linalg.eigvalsh(stiffness))[:N], rtol=1e-10)
    # its own point and stiffness: a mid-span stop leaves the first mode lower than the tip's
    assert several["contacts"][1]["frequencies"][0] < several["contacts"][0]["frequencies"][0]


def test_bad_input_is_one_line(capsys, two):
    """A flat law key every contact gives its own: refused in one line, exit 2."""
    two.write_text(CONTACTS.replace("clearance = 1e-5\n", "clearance = 1e-5\nstiffness = 1e4\n"))
    assert main(["modes", "--params", str(two), "--contact-stiffness", "2e4"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("impactbeams: error:") and len(err.strip().splitlines()) == 1
    assert "contact_stiffness" in err
