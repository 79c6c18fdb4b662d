"""First-impact maps by columns (one shared modal response per column) against the
cell-by-cell search, on the shipped sweeps and on grazing cells."""

import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from impactbeams.kernels import first_impact as fi
from impactbeams.kernels.drive import gap_harmonic
from impactbeams.kernels.events import GAVE_UP, evaluate, search_root
from impactbeams.kernels.layout import (
    CELL_CLEARANCE,
    CELL_F0,
    CELL_FORCING_FREQUENCY,
    FREE,
    GEO_C1,
    GEO_START,
    ROW_EVENT,
    ROW_FREQUENCY,
)
from impactbeams.kernels.propagation import advance
from impactbeams.kernels.records import EventFunction, Oscillators
from impactbeams.kernels.rotor import rotor_arrays
from impactbeams.model import build_free_phase
from impactbeams.packing import free_tables, geometry_row
from impactbeams.params import Params
from impactbeams.sweep.definition import load_sweep, sweep_from_mapping
from impactbeams.sweep.plan import build_plan, chunk_cells, first_impact_columns
from references import free_tip_gap

SWEEPS = Path(__file__).parents[1] / "sweeps"
EPS = np.finfo(float).eps


def maps(sweep):
    """The sweep's cells, plan and first impact times by columns and cell by cell."""
    plan = build_plan(sweep)
    cells = chunk_cells(sweep, plan, 0, sweep.size)
    columns = first_impact_columns(sweep, 0, sweep.size)
    assert columns.bounds.size - 1 < sweep.size  # the sweep has columns of several cells
    by_column, by_cell = np.empty(sweep.size), np.empty(sweep.size)
    fi.first_impact_map_parallel(cells, columns.bounds, columns.key, plan.tables, plan.geometry,
                                 sweep.t_max, by_column)
    fi.first_impact_cells(cells, plan.tables, plan.geometry, sweep.t_max, by_cell)
    return cells, plan, by_column, by_cell


def round_off_band(cell, plan, t):
    """How far (s) a root at t can move within the gap's round-off rule: twice the rule's
    width over the gap's slope at t, plus 8 ulps of t (Newton's own stop). The width is taken
    over the terms of either evaluation of the gap: the cell's (its terms at t) and the
    column's, which adds the modes' steady states |b_j A_j / D_j| and the quasi-static term
    c1 F0 (it evaluates them apart from the transients). Late in a run the rounding of the
    oscillations' phases adds eps omega t times each oscillating term (eps Omega t for the
    forced ones): over the slope, a band that Newton's steps wander in, twice."""
    g = int(cell[-1])
    table = plan.tables[g, FREE]
    work = np.empty((7, table.shape[1]))
    force = np.empty(table.shape[1], dtype=complex)
    n = fi._load_moving_modes(cell, table, work, force, plan.geometry[g, GEO_START])
    q, v = np.empty(n), np.empty(n)
    advance(work[0, :n], work[1, :n], 0.0, t, work[2, :n], work[3, :n], force[:n],
            cell[CELL_FORCING_FREQUENCY], q, v)
    harmonic = gap_harmonic(cell, plan.geometry[g])  # -c1 F0, and the shaker's U0 term
    _, slope, scale = evaluate(q, v, t, EventFunction(work[4, :n], cell[CELL_CLEARANCE],
                                                      complex(harmonic, 0.0),
                                                      cell[CELL_FORCING_FREQUENCY]))
    omega, zeta, big_omega = work[2, :n], work[3, :n], cell[CELL_FORCING_FREQUENCY]
    steady = np.abs(work[4, :n] * force[:n]
                    / (omega**2 - big_omega**2 + 2j * zeta * omega * big_omega))
    forced = abs(harmonic) + steady.sum()
    scale += forced
    damped = omega * np.sqrt(1.0 - zeta**2)
    transient = np.abs(work[4, :n]) * np.hypot(q, (v + zeta * omega * q) / damped)
    phases = big_omega * t * forced + t * np.sum(omega * transient)
    return (2.0 * fi.TOUCH_TOLERANCE * EPS * scale + 2.0 * EPS * phases) / abs(slope) \
        + 8.0 * np.spacing(t)


@pytest.mark.parametrize(("name", "thinned"), [("fig5a-omega-force.toml", "omega"),
                                               ("fig5b-clearance-force.toml", None),
                                               ("omega-clearance.toml", None)])
def test_columns_equal_the_cell_by_cell_search_on_the_shipped_sweeps(name, thinned):
    sweep = load_sweep(SWEEPS / name)
    if thinned:  # every 10th column of the 10^6-cell map: 10^5 cells
        axes = {a.name: {"min": float(a.values[0]), "max": float(a.values[-1]), "num": a.num,
                         "scale": a.scale} for a in sweep.axes}
        axes[thinned]["num"] //= 10
        sweep = sweep_from_mapping({"t_max": sweep.t_max, "n_modes": sweep.n_modes,
                                    "observables": list(sweep.observables),
                                    "params": {"clearance": sweep.base.clearance}, "axes": axes})
    assert_columns_match_cells(sweep, 200)


def assert_columns_match_cells(sweep, checked):
    """The same classification by columns as cell by cell, over 20 % of the cells impacting,
    and the times within the gap's round-off band (the ``checked`` largest differences)."""
    cells, plan, by_column, by_cell = maps(sweep)
    assert np.array_equal(np.isnan(by_column), np.isnan(by_cell))
    assert not np.isinf(by_column).any()
    hit = np.flatnonzero(~np.isnan(by_cell))
    assert hit.size > 0.2 * sweep.size
    difference = np.abs(by_column[hit] - by_cell[hit])
    for i in hit[np.argsort(difference)[-checked:]]:
        assert abs(by_column[i] - by_cell[i]) <= round_off_band(cells[i], plan, by_cell[i]), i


BENCHMARK_MAPS = Path(__file__).parents[1] / "benchmarks" / "maps"


def thinned(path, axis, keep):
    """The sweep of ``path`` with every ``keep``-th value of ``axis`` (its ends kept)."""
    with open(path, "rb") as file:
        mapping = tomllib.load(file)
    spec = mapping["axes"][axis]
    spec["num"] = (spec["num"] - 1) // keep + 1
    return sweep_from_mapping(mapping)


@pytest.mark.parametrize(("name", "axis"), [("uplift-omega-force.toml", "omega"),
                                            ("stop-omega-force.toml", "omega"),
                                            ("shaker-omega-amplitude.toml", "omega"),
                                            ("force-clearance.toml", "force_amplitude")])
def test_columns_equal_the_cell_by_cell_search_on_the_benchmark_maps(name, axis):
    """Issue 24's maps (benchmarks/maps/), every 100th column: uplifted beams (two responses
    per column), a stop, a shaker, columns along the clearance."""
    assert_columns_match_cells(thinned(BENCHMARK_MAPS / name, axis, 100), 100)


def test_the_shipped_shaker_map_by_columns_equals_the_cell_by_cell_search():
    """sweeps/stop-shaker-omega-amplitude.toml (beam 1 against a stop, the shaker carrying the
    clamp and the stop, U0 up to 1e-2 m), every 100th column: columns along U0."""
    assert_columns_match_cells(thinned(SWEEPS / "stop-shaker-omega-amplitude.toml", "omega",
                                       100), 100)


def test_a_column_near_resonance_follows_its_flanks(free, monkeypatch):
    """At Omega 1541 rad/s, 1.3 rad/s below beam 1's second mode (undamped, F0 = 1 mN), that
    mode stays driven (its steady state not split off): its bounds over [0, t_max] hold the
    beat of the whole run, and certified no cell's flank, so that every cell of a column along
    the clearance fell back to the walk (80 of 80 here). The bounds over a forcing period from
    the column's state at its start (``_response_bounds`` there) certify the flanks: a few
    walks, and the times of the cell-by-cell search."""
    cells = np.array([[clearance, 1e-3, 1541.1528822055138, 0.0, 0.0, 0.0, 0.0]
                      for clearance in np.geomspace(1e-7, 1e-5, 80)])
    tables, geometry = free_tables(free)[None], geometry_row(Params(), free)[None]
    by_cell = np.empty(len(cells))
    fi.first_impact_cells(cells, tables, geometry, 1.0, by_cell)
    walks = []

    def walk(*args):
        walks.append(args[3])
        return search_walk(*args)

    search_walk = fi.walk
    monkeypatch.setattr(fi, "walk", walk)
    work, drives, rotor = fi._scratch(tables.shape[3])
    by_column = np.empty(len(cells))
    fi._shared_column.py_func(cells, 0, 1, len(cells), CELL_CLEARANCE, tables[0, FREE],
                              geometry[0], 1.0, work, drives, rotor, by_column)
    assert not np.isnan(by_cell).any()
    assert len(walks) <= 8
    np.testing.assert_allclose(by_column, by_cell, rtol=1e-12)


def test_an_uplifted_column_is_shared_and_follows_its_flanks():
    """With uplifts the column's cells share two responses (``_load_column``): cell F0's
    state is a + F0 b, to round-off of the cell's own initial state and drives."""
    sweep = thinned(BENCHMARK_MAPS / "uplift-omega-force.toml", "omega", 100)
    plan = build_plan(sweep)
    cells = chunk_cells(sweep, plan, 0, 1000)
    table, geo = plan.tables[0, FREE], plan.geometry[0]
    work, drives, _ = fi._scratch(table.shape[1])
    active, harmonics = fi._load_column(cells[0], CELL_F0, table, geo, work, drives)
    own = np.empty((7, table.shape[1])), np.empty(table.shape[1], dtype=complex)
    for cell in cells[::97]:
        assert fi._load_moving_modes(cell, table, *own) == active == 10  # both beams move
        f0 = cell[CELL_F0]
        np.testing.assert_allclose(work[fi._Q_A0, :active] + f0 * work[fi._Q_B0, :active],
                                   own[0][fi._Q_S, :active], rtol=1e-15, atol=1e-25)
        np.testing.assert_allclose(work[fi._V_A0, :active] + f0 * work[fi._V_B0, :active],
                                   own[0][fi._V_S, :active], rtol=1e-15, atol=1e-25)
        np.testing.assert_allclose(drives[fi._A, :active] + f0 * drives[fi._B, :active],
                                   own[1][:active], rtol=1e-15)
        assert harmonics[0] + f0 * harmonics[1] == -geo[GEO_C1] * f0


@pytest.fixture(scope="module")
def free():
    return build_free_phase(Params(), 5)


def grazing_clearance(free, force, omega):
    """The clearance at which the gap's deepest dip over (0, 1 s] just touches 0."""
    response = free_tip_gap(free, Params().tip_compliance[0], 0.0, force, omega)
    t = np.linspace(0, 1.0, 100001)
    k = int(np.argmin(response(t)))
    found = minimize_scalar(lambda s: float(response(s)), bounds=(t[max(k - 1, 0)], t[k + 1]),
                            method="bounded", options={"xatol": 1e-14})
    return -float(response(found.x))


def column(free, rows, key):
    """First impact times of ``rows`` (clearance, F0, Omega) walked as one column."""
    cells = np.array([[*row, 0.0, 0.0, 0.0, 0.0] for row in rows])
    out = np.empty(len(rows))
    fi.first_impact_map_serial(cells, np.array([0, len(rows)]), key, free_tables(free)[None],
                               geometry_row(Params(), free)[None], 1.0, out)
    return out


DEPTHS = np.array([-1e-3, -1e-6, -1e-10, 1e-10, 1e-6, 1e-3])  # relative, sorted


@pytest.mark.parametrize(("omega", "force"), [(50.0, 2.5e-4), (120.0, 1.5e-4), (400.0, 1e-4)])
def test_grazing_columns_are_classified_right(free, omega, force):
    """Columns through a grazing cell, within 1e-10 (relative) of tangency on either side:
    along the clearance, a clearance below the dip impacts; along F0, a larger force does."""
    graze = grazing_clearance(free, force, omega)
    along_clearance = column(free, [[graze * (1 + d), force, omega] for d in DEPTHS],
                             CELL_CLEARANCE)
    assert np.array_equal(np.isnan(along_clearance), DEPTHS > 0)
    along_force = column(free, [[graze, force * (1 + d), omega] for d in DEPTHS], CELL_F0)
    assert np.array_equal(np.isnan(along_force), DEPTHS < 0)
    # on each side of tangency the deeper dip closes first
    assert np.all(np.diff(along_clearance[DEPTHS < 0]) > 0)
    assert np.all(np.diff(along_force[DEPTHS > 0]) < 0)


def test_classification_is_monotone_at_round_off(free):
    """Clearances within +-40 eps (relative) of tangency: whatever the rule decides at this
    level, a larger clearance never impacts where a smaller one does not, cell by cell too."""
    omega, force = 120.0, 1.5e-4
    graze = grazing_clearance(free, force, omega)
    rows = [[graze * (1 + k * EPS), force, omega] for k in range(-40, 41)]
    for by in ("column", "cell"):
        if by == "column":
            out = column(free, rows, CELL_CLEARANCE)
        else:
            out = np.empty(len(rows))
            cells = np.array([[*row, 0.0, 0.0, 0.0, 0.0] for row in rows])
            fi.first_impact_cells(cells, free_tables(free)[None],
                                  geometry_row(Params(), free)[None], 1.0, out)
        touched = ~np.isnan(out)
        assert touched[0] and not touched[-1]
        assert np.all(np.diff(touched.astype(int)) <= 0), by


def test_a_search_that_reaches_its_step_cap_says_so(free):
    """The walk's step cap ends a search with GAVE_UP (-inf), never a spin or a wrong NaN:
    one undamped mode driven at 100 rad/s from rest, whose gap (half its steady amplitude
    above 0) closes after several steps."""
    table = free_tables(free)[FREE]
    omega, weights = table[ROW_FREQUENCY, :1], table[ROW_EVENT, :1]
    drive = np.array([1e-3 + 0j])
    steady = abs(weights[0] * drive[0] / (omega[0] ** 2 - 100.0**2))
    rest = np.zeros(1)
    args = (rest, rest, 0.0, 0.0, 1.0, Oscillators(omega, np.zeros(1), drive, 100.0),
            EventFunction(weights, 0.5 * steady, 0j, 100.0), fi.TOUCH_TOLERANCE)
    work = np.empty(1), np.empty(1), rotor_arrays(1)
    assert search_root(*args, 1, *work) == GAVE_UP
    assert 0.0 < search_root(*args, 10**6, *work) < 1.0


@pytest.mark.parametrize("n_blocks", [1, 2, 8, 64])
def test_blocks_deal_every_thread_an_interleaved_share_of_the_columns(n_blocks):
    """prange's static schedule gives each of T threads (a power of two up to n_blocks) a
    contiguous range of blocks; by bit reversal thread k then takes the columns c = k mod T
    (at one block per column, Fig. 5a's resonance fell to one of two threads)."""
    residues = [fi._residue(block, n_blocks) for block in range(n_blocks)]
    assert sorted(residues) == list(range(n_blocks))  # every column in exactly one block
    threads = 1
    while threads <= n_blocks:
        per_thread = n_blocks // threads
        for k in range(threads):
            share = residues[k * per_thread:(k + 1) * per_thread]
            assert all(r % threads == residues[k * per_thread] % threads for r in share)
        threads *= 2
