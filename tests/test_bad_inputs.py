"""Every bad input is refused before any work: one line, exit code 2, no traceback, no file.

The table runs the command line in-process (``impactbeams.cli.main``) in a scratch folder. A
case passes only if the input is refused before anything is computed (the kernels are never
compiled here: a case that reached the compute would take seconds and exit 0) and before any
file or folder appears.
"""

import itertools
import time
import tracemalloc
import warnings

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from impactbeams.cli import _attach_negative_values, main
from impactbeams.contact import build_free_phase
from impactbeams.io import write_netcdf
from impactbeams.params import MAX_DEFLECTION, ParameterError, Params, check_joint
from impactbeams.preflight import check_run
from impactbeams.sweep import Axis, load_sweep, map_dataset, sweep_from_mapping
from impactbeams.trajectory import simulate

GOOD = ('t_max = 0.3\nn_modes = 4\n[params]\nclearance = 1.1e-5\n'
        '[axes.omega]\nmin = 50.0\nmax = 200.0\nnum = 2\n')
OMEGA_AXIS = "[axes.omega]\nmin = 10.0\nmax = 400.0\nnum = 3\n"
FORCE_AXIS = "[axes.force_amplitude]\nmin = 1e-4\nmax = 1e-3\nnum = 3\n"


def sweep_file(top="", params="", axes=OMEGA_AXIS):
    """A sweep TOML: top-level lines, a [params] table's lines, the axes' tables."""
    return f"t_max = 0.3\nn_modes = 4\n{top}\n[params]\n{params}\n{axes}"


def axis(name, low, high, num, scale="linear"):
    return f"[axes.{name}]\nmin = {low}\nmax = {high}\nnum = {num}\nscale = \"{scale}\"\n"


CONTINUATION = ('[params]\ncounterpart = "stop"\n[continuation]\nparameter = "omega"\n'
                'min = 100.0\nmax = 250.0\n')

# each command's usage line, printed above an error in its arguments
USAGE = {"modes": "[--n N] [--json] [PARAMETER OPTIONS]",
         "simulate": "--t-max SECONDS -o RUN.nc [OPTIONS] [PARAMETER OPTIONS]",
         "run": "SWEEP.toml [-o OUT.nc] [OPTIONS]",
         "contacts": "--t-max SECONDS [OPTIONS] [PARAMETER OPTIONS]",
         "continue": "CONTINUATION.toml [-o OUT.nc] [--quiet]",
         "plot": "IN.nc [-o OUT.png] [OPTIONS]"}

# name of a case: (arguments, {file name: TOML text} to create, fragments the message must hold)
CASES = {
    # --- modes: options, parameter values, --params files
    "modes-params-folder": (["modes", "--params", "."], {}, ["--params file '.' is a folder"]),
    "modes-params-missing": (["modes", "--params", "missing.toml"], {}, ["does not exist"]),
    "modes-params-syntax": (["modes", "--params", "p.toml"], {"p.toml": "[params\n"},
                            ["p.toml is not valid TOML"]),
    "modes-params-binary": (["modes", "--params", "p.toml"], {"p.toml": b"\xff\xfe\x00"},
                            ["p.toml is not valid TOML"]),
    "modes-params-5": (["modes", "--params", "p.toml"], {"p.toml": "params = 5\n"},
                       ["params in p.toml = 5", "must be a table"]),
    "modes-params-other-table": (["modes", "--params", "p.toml"], {"p.toml": "[other]\na = 1\n"},
                                 ["unknown key 'other' in p.toml"]),
    "modes-params-table-typo": (["modes", "--params", "p.toml"], {"p.toml": "[param]\nl1 = 0.1\n"},
                                ["unknown key 'param' in p.toml (did you mean 'params'?): a "
                                 "parameters file has only a [params] table"]),
    "modes-params-unknown": (["modes", "--params", "p.toml"], {"p.toml": "[params]\nforce = 1\n"},
                             ["unknown parameter 'force'"]),
    "modes-params-string": (["modes", "--params", "p.toml"],
                            {"p.toml": "[params]\nclearance = \"1e-5\"\n"},
                            ["clearance = '1e-5'", "finite real number"]),
    "modes-params-bool": (["modes", "--params", "p.toml"], {"p.toml": "[params]\nl1 = true\n"},
                          ["l1 = True"]),
    "modes-l1-1e300": (["modes", "--l1", "1e300"], {}, ["l1 = 1e+300", "from 1e-06 to 1000"]),
    "modes-l1-1e-300": (["modes", "--l1", "1e-300"], {}, ["l1 = 1e-300", "from 1e-06 to 1000"]),
    "modes-EI1-1e300": (["modes", "--EI1", "1e300"], {}, ["EI1 = 1e+300"]),
    "modes-rhoA2-tiny": (["modes", "--rhoA2", "1e-30"], {}, ["rhoA2 = 1e-30"]),
    "modes-E1-huge": (["modes", "--E1", "1e20"], {}, ["E1 = 1e+20"]),
    "modes-thickness1-0": (["modes", "--thickness1", "0"], {}, ["thickness1 = 0.0", "> 0"]),
    "modes-fundamental-1e12": (["modes", "--EI1", "1e10", "--rhoA1", "1e-10"], {},
                               ["l1 = 0.1", "fundamental frequency", "3.52e+12 rad/s"]),
    "modes-n-float": (["modes", "--n", "2.5"], {}, ["argument --n: '2.5'", "integer from 1"]),
    "modes-n-0": (["modes", "--n", "0"], {}, ["argument --n: 0", "integer from 1 to 200"]),
    "modes-n-10000": (["modes", "--n", "10000"], {}, ["argument --n: 10000", "1 to 200"]),
    "modes-clearance-negative": (["modes", "--clearance", "-1e-5"], {},
                                 ["clearance = -1e-05 is not allowed: must be > 0 (m)"]),
    "modes-clearance-text": (["modes", "--clearance", "abc"], {},
                             ["argument --clearance: 'abc' is not a number"]),
    "modes-clearance-nan": (["modes", "--clearance", "nan"], {}, ["clearance = nan"]),
    "modes-clearance-large": (["modes", "--clearance", "0.05"], {},
                              ["clearance = 0.05", f"{MAX_DEFLECTION:g} (l1 + l2) = 0.044 m"]),
    "modes-EI1-inf": (["modes", "--EI1", "inf"], {}, ["EI1 = inf"]),
    "modes-EI-and-material": (["modes", "--EI1", "1.0", "--E1", "2e11"], {},
                              ["both EI1 and material keys E1"]),
    "modes-damping-1": (["modes", "--damping-ratio", "1"], {}, ["damping_ratio = 1.0"]),
    "modes-damping-negative": (["modes", "--damping-ratio", "-0.1"], {},
                               ["damping_ratio = -0.1"]),
    "modes-contact-law": (["modes", "--contact-law", "rigid"], {},
                          ["argument --contact-law: invalid choice: 'rigid'"]),
    "modes-contact-stiffness": (["modes", "--contact-stiffness", "1e13"], {},
                                ["contact_stiffness = 10000000000000.0", "<= 1e+12"]),
    "modes-uplift-gap": (["modes", "--uplift2", "1e-4"], {}, ["uplift2 = 0.0001", "initial gap"]),
    "modes-uplift-large": (["modes", "--uplift1", "-0.05"], {}, ["uplift1 = -0.05"]),
    "modes-omega-1e50": (["modes", "--omega", "1e50"], {}, ["omega = 1e+50", "<= 1e+12"]),
    "modes-force-1e300": (["modes", "--force", "1e300"], {}, ["force_amplitude = 1e+300",
                                                              "force_amplitude <= "]),
    "modes-unknown-option": (["modes", "--bogus", "1"], {}, ["unrecognized arguments: --bogus"]),
    "no-command": ([], {}, ["required: command"]),
    # --- simulate: values, the run's size, the output path
    # --- contacts: the horizon, modes, the output, flat keys beside contacts
    "contacts-t-max-1e9": (["contacts", "--t-max", "1e9"], {}, ["t_max = 1000000000.0",
                                                               "t_max <= "]),
    "contacts-t-max-0": (["contacts", "--t-max", "0"], {}, ["t_max = 0.0"]),
    "contacts-no-t-max": (["contacts"], {}, ["the following arguments are required: --t-max"]),
    "contacts-output-png": (["contacts", "--t-max", "0.01", "-o", "r.png"], {},
                            ["-o/--output 'r.png'", ".nc"]),
    "contacts-clearance-unused": (
        ["contacts", "--t-max", "0.01", "--params", "p.toml", "--clearance", "1e-6"],
        {"p.toml": '[params]\ncounterpart = "stop"\n[[params.contacts]]\nclearance = 2e-6\n'
                   '[[params.contacts]]\nside = "above"\nclearance = 3e-6\n'},
        ["clearance = 1e-06 in the command line", "each of the 2 contacts gives its own"]),
    "simulate-t-max-1e9": (["simulate", "--t-max", "1e9", "-o", "r.nc"], {},
                           ["t_max = 1000000000.0", "t_max <= "]),
    "simulate-dt-output-1e-12": (["simulate", "--t-max", "0.6", "--dt-output", "1e-12", "-o",
                                  "r.nc"], {}, ["dt_output = 1e-12", "memory"]),
    "simulate-dt-output-0": (["simulate", "--t-max", "0.1", "--dt-output", "0", "-o", "r.nc"],
                             {}, ["dt_output = 0.0", "> 0"]),
    "simulate-t-max-0": (["simulate", "--t-max", "0", "-o", "r.nc"], {}, ["t_max = 0.0"]),
    "simulate-t-max-negative": (["simulate", "--t-max", "-1", "-o", "r.nc"], {},
                                ["t_max = -1.0"]),
    "simulate-t-max-inf": (["simulate", "--t-max", "inf", "-o", "r.nc"], {}, ["t_max = inf"]),
    "simulate-t-max-text": (["simulate", "--t-max", "1s", "-o", "r.nc"], {},
                            ["argument --t-max: '1s' is not a number"]),
    "simulate-n-modes-10000": (["simulate", "--t-max", "0.1", "--n-modes", "10000", "-o",
                                "r.nc"], {}, ["argument --n-modes: 10000", "1 to 200"]),
    "simulate-output-txt": (["simulate", "--t-max", "0.1", "-o", "r.txt"], {},
                            ["'r.txt' is not allowed", "must end in .nc"]),
    "simulate-output-folder": (["simulate", "--t-max", "0.1", "-o", "folder.nc"], {},
                               ["'folder.nc' is an existing folder"]),
    "simulate-output-proc": (["simulate", "--t-max", "0.1", "-o", "/proc/r.nc"], {},
                             ["'/proc/r.nc' cannot be written"]),
    "simulate-output-under-file": (["simulate", "--t-max", "0.1", "-o", "ok.toml/r.nc"], {},
                                   ["'ok.toml' is a file, not a folder"]),
    "simulate-force-1e300": (["simulate", "--t-max", "0.1", "--force", "1e300", "-o", "r.nc"],
                             {}, ["force_amplitude = 1e+300"]),
    "simulate-omega-1e50": (["simulate", "--t-max", "0.1", "--omega", "1e50", "-o", "r.nc"], {},
                            ["omega = 1e+50"]),
    "simulate-no-t-max": (["simulate", "-o", "r.nc"], {}, ["required: --t-max"]),
    "simulate-no-output": (["simulate", "--t-max", "0.1"], {}, ["required: -o/--output"]),
    # --- run: the sweep file, the output, the options
    "run-folder": (["run", "."], {}, ["sweep file '.' is a folder"]),
    "run-missing": (["run", "missing.toml"], {}, ["sweep file 'missing.toml' does not exist"]),
    "run-output-folder-nc": (["run", "ok.toml", "-o", "folder.nc"], {},
                             ["'folder.nc' is an existing folder"]),
    "run-output-folder": (["run", "ok.toml", "-o", "."], {}, ["'.' is not allowed",
                                                              "must end in .nc"]),
    "run-output-text-file": (["run", "ok.toml", "-o", "text.nc"], {},
                             ["output file 'text.nc' is not a readable netCDF file"]),
    "run-output-empty-file": (["run", "ok.toml", "-o", "empty.nc"], {},
                              ["output file 'empty.nc' is not a readable netCDF file"]),
    "run-output-foreign": (["run", "ok.toml", "-o", "foreign.nc"], {},
                           ["foreign.nc exists and holds a different result"]),
    "run-output-other-sweep": (["run", "ok.toml", "-o", "map.nc"], {},
                               ["map.nc exists and holds a different result"]),
    "run-output-proc": (["run", "ok.toml", "-o", "/proc/out.nc"], {},
                        ["'/proc/out.nc' cannot be written"]),
    "run-output-under-file": (["run", "ok.toml", "-o", "ok.toml/out.nc"], {},
                              ["'ok.toml' is a file, not a folder"]),
    "run-output-txt": (["run", "ok.toml", "-o", "out.txt"], {}, ["'out.txt' is not allowed",
                                                                 "must end in .nc"]),
    "run-scheduler": (["run", "ok.toml", "--scheduler", "not-an-address"], {},
                      ["--scheduler 'not-an-address' is not allowed"]),
    "run-scheduler-and-local": (["run", "ok.toml", "--scheduler", "tcp://h:1",
                                 "--local-cluster", "2"], {}, ["not allowed with argument"]),
    "run-threads-0": (["run", "ok.toml", "--threads", "0"], {}, ["argument --threads: 0"]),
    "run-threads-many": (["run", "ok.toml", "--threads", "100000"], {},
                         ["threads = 100000 is not allowed"]),
    "run-chunk-cells-0": (["run", "ok.toml", "--chunk-cells", "0"], {},
                          ["argument --chunk-cells: 0"]),
    "run-local-cluster-0": (["run", "ok.toml", "--local-cluster", "0"], {},
                            ["argument --local-cluster: 0"]),
    # --- sweep files
    "sweep-params-5": (["run", "s.toml"], {"s.toml": "params = 5\n" + OMEGA_AXIS},
                       ["params in s.toml = 5"]),
    "sweep-axes-5": (["run", "s.toml"], {"s.toml": "axes = 5\n"}, ["axes in s.toml = 5"]),
    "sweep-no-axes": (["run", "s.toml"], {"s.toml": "t_max = 0.3\n"}, ["[axes] of s.toml"]),
    "sweep-axis-5": (["run", "s.toml"], {"s.toml": "[axes]\nomega = 5\n"},
                     ["[axes.omega] of s.toml = 5"]),
    "sweep-EI1-and-thickness-axis": (
        ["run", "s.toml"], {"s.toml": sweep_file(params="EI1 = 1e-3",
                                                 axes=axis("thickness1", 4e-4, 5e-4, 3))},
        ["beam 1 of s.toml", "EI1 ([params])", "thickness1 ([axes])"]),
    "sweep-fixed-and-axis": (["run", "s.toml"], {"s.toml": sweep_file(params="omega = 50.0")},
                             ["omega is given both in [params]", "[axes.omega]"]),
    "sweep-law-fixed-and-axis": (
        ["run", "s.toml"],
        {"s.toml": sweep_file(top='observables = ["impact_count"]', params='contact_law = "tied"',
                              axes='[axes.contact_law]\nvalues = ["tied", "spring"]\n')},
        ["contact_law is given both"]),
    "sweep-num-2-63": (  # its cost is estimated without building the axis' 2^63 values
        ["run", "s.toml"], {"s.toml": sweep_file(axes=axis("uplift1", -1e-5, 1e-5, 2**63 - 1))},
        ["is not allowed: the run needs about", "of disk space"]),
    "sweep-num-1-range": (["run", "s.toml"], {"s.toml": sweep_file(axes=axis("omega", 10, 400, 1))},
                          ["num in [axes.omega] of s.toml = 1", "num >= 2, or max = min"]),
    "sweep-observables-string": (["run", "s.toml"],
                                 {"s.toml": sweep_file(top='observables = "first_impact_time"')},
                                 ["observables in s.toml = 'first_impact_time'", "list"]),
    "sweep-observables-empty": (["run", "s.toml"], {"s.toml": sweep_file(top="observables = []")},
                                ["observables in s.toml = []"]),
    "sweep-observables-unknown": (["run", "s.toml"],
                                  {"s.toml": sweep_file(top='observables = ["bogus"]')},
                                  ["unknown observable 'bogus' in the observables of s.toml"]),
    "sweep-omega-axis-1e300": (["run", "s.toml"],
                               {"s.toml": sweep_file(axes=axis("omega", 10, 1e300, 3))},
                               ["axis 'omega'", "omega = 1e+300", "<= 1e+12"]),
    "sweep-l1-axis-100000": (["run", "s.toml"],
                             {"s.toml": sweep_file(axes=axis("l1", 0.05, 0.1, 100000))},
                             ["l1: num = 100000", "at most 10000"]),
    "sweep-force-axis-1e300": (
        ["run", "s.toml"],
        {"s.toml": sweep_file(axes=axis("force_amplitude", 1e-3, 1e300, 3, "log"))},
        ["force_amplitude = 1e+300"]),
    # streamed, its memory is a chunk's; the disk it would fill refuses it (17 bytes a cell)
    "sweep-1e12-cells": (["run", "s.toml"], {"s.toml": sweep_file(
        axes=axis("omega", 10, 400, 1000000) + axis("force_amplitude", 1e-6, 1e-3, 1000000))},
        ["-o/--output", "15.5 TiB of disk space"]),
    "sweep-t-max-1e9": (["run", "s.toml"], {"s.toml": "t_max = 1e9\n" + OMEGA_AXIS},
                        ["t_max = 1000000000.0"]),
    "sweep-t-max-string": (["run", "s.toml"], {"s.toml": 't_max = "1"\n' + OMEGA_AXIS},
                           ["t_max in s.toml = '1'"]),
    "sweep-t-max-nan": (["run", "s.toml"], {"s.toml": "t_max = nan\n" + OMEGA_AXIS},
                        ["t_max in s.toml = nan"]),
    "sweep-n-modes-201": (["run", "s.toml"], {"s.toml": "n_modes = 201\n" + OMEGA_AXIS},
                          ["n_modes in s.toml = 201"]),
    "sweep-n-modes-float": (["run", "s.toml"], {"s.toml": "n_modes = 5.0\n" + OMEGA_AXIS},
                            ["n_modes in s.toml = 5.0"]),
    "sweep-n-modes-bool": (["run", "s.toml"], {"s.toml": "n_modes = true\n" + OMEGA_AXIS},
                           ["n_modes in s.toml = True"]),
    "sweep-unknown-key": (["run", "s.toml"], {"s.toml": "tmax = 1.0\n" + OMEGA_AXIS},
                          ["'tmax' in s.toml"]),
    "sweep-unknown-parameter": (["run", "s.toml"], {"s.toml": sweep_file(params="clearence = 1")},
                                ["unknown parameter 'clearence'"]),
    "sweep-unknown-axis": (["run", "s.toml"], {"s.toml": axis("omegaa", 1, 2, 2)},
                           ["unknown parameter 'omegaa' in [axes] of s.toml (did you mean "
                            "'omega'?)"]),
    "sweep-params-string": (["run", "s.toml"],
                            {"s.toml": sweep_file(params='clearance = "1e-5"')},
                            ["clearance = '1e-5'"]),
    "sweep-scale": (["run", "s.toml"], {"s.toml": sweep_file(axes=axis("omega", 1, 2, 2, "cube"))},
                    ["scale in [axes.omega] of s.toml = 'cube'"]),
    "sweep-log-min-0": (["run", "s.toml"],
                        {"s.toml": sweep_file(axes=axis("omega", 0, 2, 2, "log"))},
                        ["min in [axes.omega]", "needs min > 0"]),
    "sweep-reversed": (["run", "s.toml"], {"s.toml": sweep_file(axes=axis("omega", 5, 2, 3))},
                       ["max in [axes.omega]", "empty or reversed"]),
    "sweep-num-0": (["run", "s.toml"], {"s.toml": sweep_file(axes=axis("omega", 1, 2, 0))},
                    ["num in [axes.omega] of s.toml = 0"]),
    "sweep-num-float": (["run", "s.toml"], {"s.toml": sweep_file(axes=axis("omega", 1, 2, 2.5))},
                        ["num in [axes.omega] of s.toml = 2.5"]),
    "sweep-min-nan": (["run", "s.toml"], {"s.toml": sweep_file(axes=axis("omega", "nan", 2, 2))},
                      ["min in [axes.omega] of s.toml = nan"]),
    "sweep-axis-step": (["run", "s.toml"],
                        {"s.toml": sweep_file(axes=OMEGA_AXIS + "step = 1\n")},
                        ["'step' in [axes.omega]"]),
    "sweep-axis-no-max": (["run", "s.toml"],
                          {"s.toml": sweep_file(axes="[axes.omega]\nmin = 1\nnum = 2\n")},
                          ["max in [axes.omega] of s.toml", "is required"]),
    "sweep-law-axis": (["run", "s.toml"],
                       {"s.toml": sweep_file(axes='[axes.contact_law]\nvalues = ["rigid"]\n')},
                       ["values in [axes.contact_law] of s.toml"]),
    "sweep-gap": (["run", "s.toml"], {"s.toml": sweep_file(axes=axis("uplift2", 0, 2e-5, 3))},
                  ["uplift2 = 2e-05", "initial gap"]),
    "sweep-clearance-axis-large": (["run", "s.toml"], {"s.toml": sweep_file(
        params="", axes=axis("clearance", 1e-5, 0.05, 3))},
        ["at the grid point clearance = 0.05", "clearance = 0.05"]),
    "sweep-damping-axis": (["run", "s.toml"],
                           {"s.toml": sweep_file(axes=axis("damping_ratio", 0.5, 1.0, 3))},
                           ["axis 'damping_ratio'", "damping_ratio = 1.0"]),
    "sweep-E1-axis": (["run", "s.toml"], {"s.toml": sweep_file(axes=axis("E1", 1e9, 1e20, 3))},
                      ["axis 'E1'", "E1 = 1e+20"]),
    "sweep-syntax": (["run", "s.toml"], {"s.toml": "t_max = \n"}, ["s.toml is not valid TOML"]),
    # --- issue 20: tracebacks, unclear and silent cases
    "sweep-t-max-1e9-fixed-omega": (
        ["run", "s.toml"], {"s.toml": sweep_file(params="omega = 50.0", axes=FORCE_AXIS).replace(
            "t_max = 0.3", "t_max = 1e9")},
        ["at every grid point of s.toml: t_max = 1000000000.0", "t_max <= "]),
    "sweep-transient-1e9-fixed-omega": (
        ["run", "s.toml"], {"s.toml": sweep_file(
            top='observables = ["response_period"]\ntransient_periods = 1000000000',
            params="omega = 50.0", axes=FORCE_AXIS)},
        ["at every grid point of s.toml: transient_periods + sampled_periods", "fewer periods"]),
    "sweep-transient-first-impact": (
        ["run", "s.toml"], {"s.toml": sweep_file(top="transient_periods = 20")},
        ["transient_periods in s.toml = 20 is not allowed: only lyapunov_exponent, "
         "poincare_deflection1", "observables here: first_impact_time"]),
    "sweep-observables-twice": (
        ["run", "s.toml"],
        {"s.toml": sweep_file(top='observables = ["first_impact_time", "first_impact_time"]')},
        ["observables in s.toml = ['first_impact_time', 'first_impact_time']", "once"]),
    "sweep-material-list": (["run", "s.toml"], {"s.toml": sweep_file(params='E1 = ["x"]')},
                            ["E1 = ['x']", "finite real number"]),
    "modes-params-rho1-empty-list": (["modes", "--params", "p.toml"],
                                     {"p.toml": "[params]\nrho1 = []\n"},
                                     ["rho1 = [] is not allowed: must be a finite real number"]),
    "modes-params-width1-list": (["modes", "--params", "p.toml"],
                                 {"p.toml": '[params]\nwidth1 = ["x"]\n'}, ["width1 = ['x']"]),
    "modes-params-thickness1-list": (["modes", "--params", "p.toml"],
                                     {"p.toml": "[params]\nthickness1 = [1, 2]\n"},
                                     ["thickness1 = [1, 2]"]),
    "simulate-lyapunov-t-max-short": (
        ["simulate", "--t-max", "0.05", "--lyapunov", "1", "--transient-periods", "100", "-o",
         "r.nc"], {},
        ["t_max = 0.05 is not allowed", "forcing periods 2 pi / omega of 0.125664 s",
         "t_max holds 0 of them", "t_max >= (transient_periods + 1) x 0.125664 s = 12.692 s"]),
    "simulate-lyapunov-transient-long": (
        ["simulate", "--t-max", "1", "--lyapunov", "1", "--transient-periods", "100", "-o",
         "r.nc"], {}, ["t_max holds 7 of them", "or transient_periods <= 6"]),
    "simulate-transient-alone": (["simulate", "--t-max", "0.05", "--transient-periods", "3", "-o",
                                  "r.nc"], {}, ["transient_periods = 3", "this run has neither"]),
    "simulate-contact-damping-overdamped": (
        ["simulate", "--t-max", "0.05", "--contact-damping", "1e6", "--contact-stiffness", "1e4",
         "-o", "r.nc"], {},
        ["contact_damping = 1000000.0 is not allowed: with contact_stiffness = 10000 N/m",
         "at most about 1.35 N s/m"]),
    "simulate-contact-damping-beyond-float-range": (  # c_e w w^T overflows: overdamped too
        ["simulate", "--t-max", "0.05", "--contact-damping", "1e308", "-o", "r.nc"], {},
        ["contact_damping = 1e+308 is not allowed", "at most about"]),
    "run-contact-damping-overdamped": (  # 4 modes: before its plan is printed or a file made
        ["run", "s.toml"],
        {"s.toml": sweep_file(top='observables = ["impact_count"]',
                              params="contact_damping = 1e6\ncontact_stiffness = 1e4")},
        ["contact_damping = 1000000.0 is not allowed: with contact_stiffness = 10000 N/m",
         "at most about 3.52 N s/m"]),
    "run-chunk-cells-1e9": (["run", "ok.toml", "--chunk-cells", "1000000000"], {},
                            ["argument --chunk-cells: 1000000000 is not allowed: must be an "
                             "integer from 1 to 16777216"]),
    # --- plot: the input file, the figure's path
    "plot-folder": (["plot", ".", "-o", "x.png"], {}, ["input file '.' is a folder"]),
    "plot-missing": (["plot", "missing.nc", "-o", "x.png"], {},
                     ["input file 'missing.nc' does not exist"]),
    "plot-empty": (["plot", "empty.nc", "-o", "x.png"], {},
                   ["input file 'empty.nc' is not a readable netCDF file"]),
    "plot-truncated": (["plot", "truncated.nc", "-o", "x.png"], {},
                       ["input file 'truncated.nc' is not a readable netCDF file"]),
    "plot-text": (["plot", "text.nc", "-o", "x.png"], {},
                  ["input file 'text.nc' is not a readable netCDF file"]),
    "plot-output-xyz": (["plot", "map.nc", "-o", "x.xyz"], {},
                        ["'x.xyz' is not allowed: a figure file must end in", ".png"]),
    "plot-output-nc": (["plot", "map.nc", "-o", "x.nc"], {}, ["'x.nc' is not allowed"]),
    "plot-output-folder": (["plot", "map.nc", "-o", "folder.png"], {},
                           ["'folder.png' is an existing folder"]),
    "plot-output-under-file": (["plot", "map.nc", "-o", "ok.toml/x.png"], {},
                               ["'ok.toml' is a file, not a folder"]),
    "plot-output-proc": (["plot", "map.nc", "-o", "/proc/x.png"], {},
                         ["'/proc/x.png' cannot be written"]),
    "plot-events-unknown": (["plot", "map.nc", "--events", "fold,gazing"], {},
                            ["--events = 'fold,gazing' is not allowed: 'gazing' is not an "
                             "event kind (did you mean 'grazing'?); give all, none, or kinds "
                             "separated by commas from fold, period_doubling"]),
    "plot-events-none-and-kinds": (["plot", "map.nc", "--events", "none,fold"], {},
                                   ["'all' and 'none' stand alone"]),
    "plot-events-on-a-map": (["plot", "map.nc", "--events", "fold"], {},
                             ["events (--events) is for a continuation's file only"]),
    # --- issue 32: no abbreviations, the nearest name, every drive's small-deflection limit
    "simulate-abbreviated-option": (
        ["simulate", "--t-max", "1", "--clear", "1e-5", "-o", "r.nc"], {},
        ["unrecognized arguments: --clear 1e-5 (did you mean '--clearance'?)"]),
    "modes-abbreviated-option": (["modes", "--contact-l", "tied"], {},
                                 ["unrecognized arguments: --contact-l tied (did you mean "
                                  "'--contact-law'?)"]),
    "sweep-top-level-typo": (["run", "s.toml"], {"s.toml": sweep_file(top="tmax = 1.0")},
                             ["unknown top-level key 'tmax' in s.toml (did you mean 't_max'?)"]),
    "sweep-params-typo": (["run", "s.toml"], {"s.toml": sweep_file(params="clearence = 1e-5")},
                          ["unknown parameter 'clearence' in [params] of s.toml (did you mean "
                           "'clearance'?)"]),
    "sweep-axis-key-typo": (["run", "s.toml"], {"s.toml": sweep_file(
        axes="[axes.omega]\nmin = 10.0\nmax = 400.0\nnun = 3\n")},
        ["unknown key 'nun' in [axes.omega] of s.toml (did you mean 'num'?)"]),
    "continue-missing": (["continue", "missing.toml"], {},
                         ["continuation file 'missing.toml' does not exist"]),
    "continue-key-typo": (["continue", "c.toml"], {"c.toml": CONTINUATION.replace("max", "mx")},
                          ["unknown key 'mx' in [continuation] of c.toml (did you mean 'max'?)"]),
    "continue-top-level-typo": (["continue", "c.toml"], {"c.toml": "tmax = 3\n" + CONTINUATION},
                                ["unknown top-level key 'tmax' in c.toml"]),
    "continue-steps-crossed": (["continue", "c.toml"],
                               {"c.toml": CONTINUATION + "min_step = 2.0\nmax_step = 1.0\n"},
                               ["min_step = 2.0 is not allowed: must be <= max_step = 1 (rad/s)"]),
    "continue-step-beyond-max": (["continue", "c.toml"],
                                 {"c.toml": CONTINUATION + "step = 5.0\nmax_step = 1.0\n"},
                                 ["step = 5.0 is not allowed: must lie from min_step = 1.5e-07 "
                                  "to max_step = 1 (rad/s)"]),
    "continue-omega-0": (["continue", "c.toml"],
                         {"c.toml": CONTINUATION.replace("min = 100.0", "min = 0.0")},
                         ["min = 0.0 is not allowed: a periodic orbit needs omega > 0"]),
    "continue-base-amplitude-beyond": (  # refused before its header, not at the range's end
        ["continue", "c.toml"],
        {"c.toml": CONTINUATION.replace('"omega"', '"base_amplitude"').replace(
            "min = 100.0\nmax = 250.0", "min = 1e-6\nmax = 0.1")},
        ["base_amplitude = 0.1 is not allowed: the shaker's motion must be <= 0.2 l1 = 0.02 m"]),
    "continue-subspace-beyond": (["continue", "c.toml"],  # before its header
                                 {"c.toml": "n_modes = 3\n" + CONTINUATION + "subspace = 50\n"},
                                 ["subspace = 50 is not allowed: must be an integer from 3 to 6"]),
    "continue-n-modes-0": (["continue", "c.toml"], {"c.toml": "n_modes = 0\n" + CONTINUATION},
                           ["n_modes = 0 is not allowed"]),
    "simulate-base-amplitude-10": (["simulate", "--t-max", "1", "--base-amplitude", "10", "-o",
                                    "r.nc"], {},
                                   ["base_amplitude = 10.0 is not allowed: the shaker's motion "
                                    "must be <= 0.2 min(l1, l2) = 0.02 m (small deflections"]),
    "simulate-base-amplitude-1e300": (["simulate", "--t-max", "1", "--base-amplitude", "1e300",
                                       "-o", "r.nc"], {}, ["base_amplitude = 1e+300"]),
    "simulate-base-amplitude-stop": (["simulate", "--t-max", "1", "--base-amplitude", "1.0",
                                      "--counterpart", "stop", "-o", "r.nc"], {},
                                     ["base_amplitude = 1.0", "<= 0.2 l1 = 0.02 m"]),
    "simulate-base-amplitude-long-beam": (
        ["simulate", "--t-max", "1", "--base-amplitude", "0.1", "--l1", "0.2", "--counterpart",
         "stop", "-o", "r.nc"], {}, ["base_amplitude = 0.1", "<= 0.2 l1 = 0.04 m"]),
    "simulate-base-amplitude-beam2": (
        ["simulate", "--t-max", "1", "--base-amplitude", "0.03", "--shaker", "beam2", "--l1",
         "0.5", "-o", "r.nc"], {}, ["base_amplitude = 0.03", "<= 0.2 l2 = 0.024 m"]),
    "sweep-base-amplitude-axis": (["run", "s.toml"], {"s.toml": sweep_file(
        params='counterpart = "stop"', axes=axis("base_amplitude", 1e-6, 0.1, 3, "log"))},
        ["base_amplitude = 0.1", "<= 0.2 l1 = 0.02 m"]),
}


def small_map(path, source="other sweep"):
    """An impactbeams map file (results filled in without computing), for reading tests."""
    sweep = sweep_from_mapping({"t_max": 0.3, "n_modes": 4, "axes": {
        "omega": {"min": 50.0, "max": 200.0, "num": 3},
        "force_amplitude": {"min": 1e-4, "max": 1e-3, "num": 2}}}, source=source)
    write_netcdf(map_dataset(sweep, {"first_impact_time": np.linspace(0.01, 0.2, 6)}), path)


@pytest.fixture
def scratch(tmp_path, monkeypatch):
    """A working folder with the files the cases refer to."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ok.toml").write_text(GOOD)
    (tmp_path / "text.nc").write_text("not netCDF\n")
    (tmp_path / "empty.nc").write_bytes(b"")
    xr.Dataset({"a": ("x", np.arange(1000.0))}).to_netcdf(tmp_path / "foreign.nc",
                                                          engine="netcdf4")
    whole = (tmp_path / "foreign.nc").read_bytes()
    (tmp_path / "truncated.nc").write_bytes(whole[: len(whole) // 2])
    (tmp_path / "folder.nc").mkdir()
    (tmp_path / "folder.png").mkdir()
    small_map(tmp_path / "map.nc")
    return tmp_path


def tree(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.mark.parametrize(("argv", "files", "fragments"), CASES.values(), ids=CASES.keys())
def test_bad_input_is_refused_with_one_line_and_nothing_written(scratch, capsys, argv, files,
                                                                 fragments):
    for name, text in files.items():
        path = scratch / name
        path.write_bytes(text) if isinstance(text, bytes) else path.write_text(text)
    before = tree(scratch)
    start = time.perf_counter()
    code = main(argv)
    elapsed = time.perf_counter() - start
    out, err = capsys.readouterr()
    assert code == 2, err
    lines = err.splitlines()
    # one line, after the command's usage line if the arguments themselves are wrong
    usage = lines[:-1]
    command = argv[0] if argv and argv[0] in USAGE else None
    assert usage in ([], [f"usage: impactbeams {command} {USAGE[command]}" if command else
                          "usage: impactbeams [-h] [--version] {modes,simulate,contacts,run,"
                          "continue,grazing,basins,plot} ..."]), err
    assert lines[-1].startswith("impactbeams: error: "), err
    for fragment in fragments:
        assert fragment in lines[-1]
    assert "Traceback" not in err and "_positive" not in err and out == ""
    assert tree(scratch) == before  # no output file, no partial folder, no results/ folder
    # refused before any work: validation is vectorised and compiles nothing (measured: at
    # most 0.5 s, the first import of Numba or matplotlib; 20 s would mean it computed)
    assert elapsed < 20


def test_the_table_covers_the_inputs_of_the_issue():
    assert len(CASES) >= 100


def test_negative_values_reach_the_checks():
    assert _attach_negative_values(["modes", "--clearance", "-1e-5", "--uplift1", "-2",
                                    "--omega=-1", "-o", "-x.nc", "--n", "-.5E+3"]) == [
        "modes", "--clearance=-1e-5", "--uplift1=-2", "--omega=-1", "-o", "-x.nc", "--n=-.5E+3"]


def test_negative_uplift_is_accepted(capsys):
    assert main(["modes", "--n", "2", "--json", "--contact-law", "tied", "--uplift1",
                 "-1e-6"]) == 0
    assert capsys.readouterr().err == ""


def test_plot_without_suffix_reports_the_file_written(scratch, capsys):
    assert main(["plot", "map.nc", "-o", "xfile"]) == 0
    assert capsys.readouterr().err == "wrote xfile.png\n"
    assert (scratch / "xfile.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not (scratch / "xfile").exists()


def test_plot_into_a_missing_folder_makes_it_as_run_does(scratch, capsys):
    assert main(["plot", "map.nc", "-o", "sub/dir/x.png"]) == 0
    assert capsys.readouterr().err == "wrote sub/dir/x.png\n"
    assert (scratch / "sub" / "dir" / "x.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert tree(scratch / "sub") == ["dir", "dir/x.png"]  # written atomically: no temporary left


def test_a_map_in_which_no_cell_impacts_is_plotted(scratch, capsys):
    sweep = load_sweep(scratch / "ok.toml")
    write_netcdf(map_dataset(sweep, {"first_impact_time": np.full(2, np.nan)}), "none.nc")
    assert main(["plot", "none.nc", "-o", "none.png"]) == 0
    assert capsys.readouterr().err == (
        "impactbeams: first_impact_time has no value in any cell (no impact by t_max = 0.3 s): "
        "drawn all grey\nwrote none.png\n")


def test_rerun_of_a_finished_sweep_says_it_reused_the_result(scratch, capsys):
    small_map(scratch / "same.nc", source="same.toml")
    (scratch / "same.toml").write_text(
        "t_max = 0.3\nn_modes = 4\n[axes.omega]\nmin = 50.0\nmax = 200.0\nnum = 3\n"
        "[axes.force_amplitude]\nmin = 1e-4\nmax = 1e-3\nnum = 2\n")
    before = (scratch / "same.nc").read_bytes()
    assert main(["run", "same.toml", "-o", "same.nc"]) == 0
    err = capsys.readouterr().err
    assert err == "reused same.nc: it already holds the result of this sweep (nothing computed)\n"
    assert (scratch / "same.nc").read_bytes() == before


def test_incomplete_cells_warn_and_exit_3(scratch, capsys):
    """A finished dynamics map with stopped cells: a one-line warning and exit code 3."""
    text = ('t_max = 0.3\nn_modes = 4\nobservables = ["impact_count"]\n'
            '[params]\ncontact_law = "tied"\n[axes.omega]\nmin = 50.0\nmax = 200.0\nnum = 5\n')
    (scratch / "dyn.toml").write_text(text)
    sweep = load_sweep(scratch / "dyn.toml")
    status = np.array([0, 1, 2, 1, 0])
    write_netcdf(map_dataset(sweep, {"impact_count": np.arange(5.0),
                                     "dynamics_status": status}), scratch / "dyn.nc")
    assert main(["run", "dyn.toml", "-o", "dyn.nc", "--quiet"]) == 3
    warning = capsys.readouterr().err.splitlines()[-1]
    assert warning == ("impactbeams: warning: 3 of 5 cells stopped before t_max (2 event_limit, "
                       "1 stuck; see dynamics_status): their observables cover only the part "
                       "before the stop")


def test_incomplete_simulation_exits_3(scratch, capsys, monkeypatch):
    import impactbeams.trajectory

    stopped = xr.Dataset({"impact": ("impact", np.arange(3))}, attrs={"status": "event_limit"})
    monkeypatch.setattr(impactbeams.trajectory, "simulate", lambda *args, **kwargs: stopped)
    assert main(["simulate", "--t-max", "0.1", "-o", "r.nc"]) == 3
    assert "status event_limit" in capsys.readouterr().err


def test_a_1e8_cell_sweep_validates_fast_without_per_cell_memory():
    mapping = {"t_max": 1.0, "n_modes": 5, "params": {"clearance": 1.1e-5}, "axes": {
        "omega": {"min": 10.0, "max": 400.0, "num": 10_000},
        "force_amplitude": {"min": 1e-6, "max": 1e-3, "num": 10_000, "scale": "log"}}}
    tracemalloc.start()
    start = time.perf_counter()
    sweep = sweep_from_mapping(mapping)
    elapsed = time.perf_counter() - start
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert sweep.size == 10**8
    # measured 5 ms and well under 1 MB; one float64 per cell would be 800 MB
    assert elapsed < 1.0 and peak < 10e6


@pytest.mark.parametrize(("kwargs", "fragment"), [
    ({"search_span": 1e-19}, "search_span = 1e-19"),
    ({"search_span": 0.0}, "search_span = 0.0"),
    ({"search_span": float("nan")}, "search_span = nan"),
    ({"max_events": 0}, "max_events = 0"),
    ({"max_events": 10**12}, "max_events = 1000000000000"),
    ({"n_points": 1}, "n_points = 1"),
    ({"n_modes": 2.5}, "n_modes = 2.5"),
    ({"n_modes": 201}, "n_modes = 201"),
    ({"dt_output": -1.0}, "dt_output = -1.0"),
    ({"times": [0.2, 0.1]}, "times"),
    ({"times": [0.0, 2.0]}, "times"),
    ({"episode_separation": -1.0}, "episode_separation = -1.0"),
    ({"dt_output": 1.5}, "dt_output = 1.5 is not allowed: must be > 0 and <= t_max = 1.0 (a "
                         "longer step stores only t = 0)"),
])
def test_simulate_refuses_bad_arguments_at_once(kwargs, fragment):
    start = time.perf_counter()
    with pytest.raises(ParameterError) as error:
        simulate(Params(), 1.0, **kwargs)
    assert fragment in str(error.value)
    assert time.perf_counter() - start < 5  # before any mode building or compute


def test_fixed_material_key_is_kept_under_a_thickness_axis():
    """E1 fixed, thickness1 swept: every geometry has EI1 = E1 b h^3 / 12 (was steel's E)."""
    sweep = sweep_from_mapping({"params": {"E1": 7e10}, "axes": {
        "thickness1": {"min": 4e-4, "max": 6e-4, "num": 3}}})
    for h in (4e-4, 5e-4, 6e-4):
        p = sweep.params_at({"thickness1": h})
        assert p.EI1 == pytest.approx(7e10 * 5e-3 * h**3 / 12, rel=1e-15)


def test_fixed_values_need_only_be_valid_with_the_axes():
    """uplift2 = 2e-5 is invalid with the default clearance but valid on this clearance axis."""
    sweep = sweep_from_mapping({"params": {"uplift2": 2e-5}, "axes": {
        "clearance": {"min": 5e-5, "max": 1e-4, "num": 2}}})
    assert sweep.base.clearance == 5e-5 and sweep.base.uplift2 == 2e-5


AXES = {"l1": (1e-3, 2.0), "EI1": (1e-6, 1.0), "thickness2": (1e-5, 1e-2),
        "force_amplitude": (1e-6, 10.0), "clearance": (1e-7, 0.1), "uplift1": (-0.02, 0.02),
        "uplift2": (-0.02, 0.02), "omega": (1.0, 1e7)}


@settings(max_examples=60, deadline=None, derandomize=True, database=None)
@given(st.lists(st.sampled_from(sorted(AXES)), min_size=1, max_size=3, unique=True),
       st.lists(st.floats(0, 1), min_size=6, max_size=6), st.sampled_from([1e-3, 1.0, 100.0]))
def test_corner_check_equals_checking_every_point(names, fractions, t_max):
    """The vectorised corner check refuses a grid exactly when some grid point is refused by
    building its Params and checking its run one point at a time (the independent check)."""
    axes = {}
    for k, name in enumerate(names):
        low, high = AXES[name]
        a, b = sorted((low + fractions[2 * k] * (high - low),
                       low + fractions[2 * k + 1] * (high - low)))
        axes[name] = {"min": a, "max": b, "num": 3} if b > a else {"min": a, "max": a, "num": 1}
    try:
        sweep_from_mapping({"t_max": t_max, "n_modes": 3, "axes": axes})
        refused = False
    except ParameterError:
        refused = True
    grid = [Axis(name, spec["min"], spec["max"], spec["num"], "linear").values
            for name, spec in axes.items()]
    every_point_ok = True
    for values in itertools.product(*grid):
        changes = dict(zip(axes, map(float, values), strict=True))
        try:
            point = Params.from_mapping(changes)
            check_joint(point.numeric())
            check_run(point.numeric(), t_max, 3)
        except ParameterError:
            every_point_ok = False
    assert refused == (not every_point_ok)


def test_a_full_disk_is_refused_before_the_run(scratch, capsys, monkeypatch):
    import shutil

    usage = shutil.disk_usage(scratch)
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage._replace(free=10))
    before = tree(scratch)
    assert main(["run", "ok.toml", "-o", "new.nc"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("impactbeams: error: -o/--output 'new.nc' is not allowed: the run "
                          "needs about ") and "10 B free" in err and err.count("\n") == 1
    assert tree(scratch) == before


def test_a_system_error_while_writing_is_one_line_with_exit_code_1(scratch, capsys, monkeypatch):
    import impactbeams.trajectory

    done = xr.Dataset({"impact": ("impact", np.arange(3))}, attrs={"status": "complete"})
    monkeypatch.setattr(impactbeams.trajectory, "simulate", lambda *args, **kwargs: done)

    def full_disk(dataset, path, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", full_disk)
    before = tree(scratch)
    assert main(["simulate", "--t-max", "0.1", "-o", "r.nc"]) == 1
    assert capsys.readouterr().err == ("impactbeams: error: could not write r.nc: No space left "
                                       "on device\n")
    assert tree(scratch) == before  # no temporary file, no lock file


def test_sweep_memory_estimate_bounds_the_measured_peak(tmp_path):
    """The estimate is an upper bound of the traced peak, within a factor of 2, of a streamed
    run (a chunk at a time, what `impactbeams run` does) and of one held in memory (the
    results, then the Dataset written), each with the part that grows with the cells
    (measured 1.6x and 1.7x)."""
    from impactbeams.sweep import run_sweep, write_sweep
    from impactbeams.sweep.estimate import expected_cost

    sweep = sweep_from_mapping({"t_max": 0.3, "n_modes": 4, "axes": {
        "omega": {"min": 50.0, "max": 200.0, "num": 500},
        "force_amplitude": {"min": 1e-4, "max": 1e-3, "num": 400}}})
    write_sweep(sweep, tmp_path / "warm.nc")  # kernels, plan, netCDF and xarray loaded
    write_netcdf(run_sweep(sweep), tmp_path / "warm-memory.nc")
    for in_memory in (False, True):
        tracemalloc.start()
        if in_memory:
            write_netcdf(run_sweep(sweep), tmp_path / "m.nc")
        else:
            write_sweep(sweep, tmp_path / "s.nc")
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        estimate = expected_cost(sweep, in_memory=in_memory).memory
        assert peak <= estimate <= 2 * peak, (in_memory, peak, estimate)


@pytest.mark.parametrize(("n_modes", "dt_output", "fields"), [
    (5, 1e-6, False), (5, 2.5e-7, False), (20, 1e-6, False), (5, 1e-6, True)])
def test_simulation_memory_estimate_bounds_the_measured_peak(tmp_path, n_modes, dt_output,
                                                             fields):
    """simulation_cost's memory bounds the traced peak of a run and its writing, within 3x
    (measured 1.8x to 2.2x; the kernels are compiled once for the whole test session)."""
    from impactbeams.trajectory.simulation import simulation_cost

    params, t_max = Params(contact_law="tied"), 0.05
    small_map(tmp_path / "warm.nc")  # compile and load the netCDF machinery outside the trace
    simulate(params, 0.001, n_modes=n_modes)
    tracemalloc.start()
    ds = simulate(params, t_max, n_modes=n_modes, dt_output=dt_output, fields=fields,
                  max_events=5000)
    write_netcdf(ds, tmp_path / "r.nc")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    estimate = simulation_cost(params, t_max, n_modes, ds.time.size, fields, 41, False,
                               5000).memory
    assert peak <= estimate <= 3 * peak


def _public_calls():
    """(call, fragments of its message) for bad arguments of the public functions."""
    import impactbeams as ib
    from impactbeams.sweep import write_sweep

    fig5a = "sweeps/fig5a-omega-force.toml"
    return {
        "run_sweep-sweep": (lambda: ib.run_sweep(5), "sweep = 5 (int) is not allowed: must be "
                            "a Sweep (load_sweep, sweep_from_mapping) or the path of a sweep"),
        "run_sweep-threads": (lambda: ib.run_sweep(fig5a, threads="2"),
                              "threads = '2' (str) is not allowed: must be None or an integer"),
        "run_sweep-output": (lambda: ib.run_sweep(fig5a, output=3), "output = 3 (int)"),
        "run_sweep-progress": (lambda: ib.run_sweep(fig5a, progress="yes"),
                               "progress = 'yes' (str) is not allowed: must be True or False"),
        "run_sweep-on_chunk": (lambda: ib.run_sweep(fig5a, on_chunk=3),
                               "on_chunk = 3 (int) is not allowed: must be None or a function"),
        "write_sweep-output": (lambda: write_sweep(fig5a, None),
                               "output = None (NoneType) is not allowed"),
        "write_sweep-runner": (lambda: write_sweep(fig5a, "x.nc", runner="local"),
                               "runner = 'local' (str)"),
        "load_sweep-path": (lambda: ib.load_sweep(None), "path = None (NoneType) is not "
                            "allowed: must be the path of a TOML file"),
        "sweep_from_mapping-data": (lambda: sweep_from_mapping("t_max = 1"),
                                    "data = 't_max = 1' (str) is not allowed: must be a mapping"),
        "sweep_from_mapping-source": (lambda: sweep_from_mapping({}, source=3),
                                      "source = 3 (int)"),
        "steady_gap-params": (lambda: ib.steady_gap(5, 5), "params = 5 (int) is not allowed: "
                              "must be an impactbeams.Params"),
        "grazing_curve-omega": (lambda: ib.grazing_curve(Params(), 5, "clearance", "fast"),
                                "omega = 'fast' is not allowed: must be a positive frequency"),
        "grazing_frequencies-brackets": (
            lambda: ib.grazing_frequencies(Params(), 5, 10.0, 20.0, brackets=2.5),
            "brackets = 2.5"),
        "basins-params": (lambda: ib.basins(5, None), "params = 5 (int) is not allowed: "
                           "must be an impactbeams.Params"),
        "basin_stability-samples": (lambda: ib.basin_stability(Params(omega=100.0), 0, ()),
                                    "samples = 0 is not allowed"),
        "Settling-window": (lambda: ib.Settling(window="24"), "window = '24'"),
        "Params-contact_law": (lambda: Params(contact_law=np.array(["tied"])),
                               "contact_law = array(['tied']"),
        "Params-l1": (lambda: Params(l1=[0.1]), "l1 = [0.1] is not allowed: must be a finite"),
        "Params.replace-rho1": (lambda: Params().replace(rho1=[]), "rho1 = []"),
        "Params.from_mapping": (lambda: Params.from_mapping([("l1", 0.1)]),
                                "mapping = [('l1', 0.1)] (list) is not allowed"),
        "Params.from_toml": (lambda: Params.from_toml(5), "path = 5 (int)"),
        "build_tied_model-params": (lambda: ib.build_tied_model(None, 3),
                               "params = None (NoneType) is not allowed: must be an "
                               "impactbeams.Params"),
        "build_tied_model-n_modes": (lambda: ib.build_tied_model(Params(), 3.0),
                                "n_modes = 3.0 is not allowed: must be an integer >= 1"),
        "build_free_phase-n_modes": (lambda: ib.build_free_phase(Params(), True),
                                     "n_modes = True"),
        "Cantilever-segments": (lambda: ib.Cantilever(()), "segments = () is not allowed: "
                                "must be one or more Segment"),
        "Segment-length": (lambda: ib.Segment(0.0, 1.0, 1.0), "Segment.length = 0.0 is not "
                           "allowed: must be a finite real number > 0 (m)"),
        "PointMass-mass": (lambda: ib.PointMass(0.1, -1.0), "PointMass.mass = -1.0 is not "
                           "allowed: must be a finite real number >= 0 (kg)"),
        "Spring-stiffness": (lambda: ib.Spring(0.1, float("nan")), "Spring.stiffness = nan is "
                             "not allowed: must be a finite real number >= 0 (N/m)"),
        "MatrixStructure-contact_dof": (
            lambda: ib.MatrixStructure(np.eye(2), np.eye(2), contact_dof=1.0, length=0.1),
            "structure1.contact_dof = 1.0 is not allowed: must be a DOF index from 0 to 1"),
        "ModalStructure-frequencies": (
            lambda: ib.ModalStructure("a", [1.0], 1.0, 1.0, 0.1),
            "structure1.frequencies = 'a' is not allowed: must be a real vector"),
        "LongTime-sampled_periods": (lambda: ib.LongTime(sampled_periods="3"),
                                     "sampled_periods = '3'"),
        "simulate-params": (lambda: simulate({"l1": 0.1}, 1.0), "params = {'l1': 0.1} (dict)"),
        "simulate-fields": (lambda: simulate(Params(), 0.1, fields="yes"), "fields = 'yes'"),
        "simulate-times": (lambda: simulate(Params(), 0.1, times=["a"]),
                           "times = ['a'] (list) is not allowed: must be an array of output"),
        "simulate-lyapunov": (lambda: simulate(Params(), 0.1, lyapunov="1"),
                              "lyapunov = '1' (str)"),
        "simulate-long_time": (lambda: simulate(Params(), 0.1, long_time=5),
                               "long_time = 5 (int) is not allowed: must be None or an "
                               "impactbeams.LongTime"),
        "simulate-transient_periods": (lambda: simulate(Params(), 0.1, transient_periods=2.5),
                                       "transient_periods = 2.5"),
        "simulate-initial_state": (lambda: simulate(Params(contact_law="tied"), 0.1, n_modes=2,
                                                    initial_state="rest"),
                                   "initial_state = 'rest' (str) is not allowed: must be 8 "
                                   "finite numbers"),
        "InitialFields-deflection1": (lambda: ib.InitialFields(deflection1=0.0),
                                      "deflection1 = 0.0 (float) is not allowed: must be None "
                                      "or a function"),
        "PeriodMap-params": (lambda: ib.PeriodMap(None), "params = None (NoneType) is not "
                             "allowed: must be an impactbeams.Params"),
        "ContactsPeriodMap-params": (lambda: ib.ContactsPeriodMap(None), "params = None "
                                     "(NoneType) is not allowed: must be an impactbeams.Params"),
        "ContactsPeriodMap-omega": (lambda: ib.ContactsPeriodMap(Params(
            omega=0.0, counterpart="stop", contacts=ib.two_sided_stop())),
            "omega = 0.0 is not allowed: a period map needs a forcing period"),
        "periodic_orbit-period": (lambda: ib.periodic_orbit(Params(), period=0),
                                  "period = 0 is not allowed"),
        "Continuation-params": (lambda: ib.Continuation(None, "omega", 1.0, 2.0),
                                "params = None (NoneType) is not allowed: must be an "
                                "impactbeams.Params"),
        "continue_orbits-continuation": (lambda: ib.continue_orbits("omega"),
                                         "continuation = 'omega' (str) is not allowed: must be "
                                         "an impactbeams.Continuation"),
        "BifurcationCurve-params": (
            lambda: ib.BifurcationCurve(None, "fold", "omega", 1.0, [], "clearance", 1.0, 2.0,
                                        0.5, 1.5, 3),
            "params = None (NoneType) is not allowed: must be an impactbeams.Params"),
        "continue_curve-curve": (lambda: ib.continue_curve("fold"),
                                 "curve = 'fold' (str) is not allowed: must be an "
                                 "impactbeams.continuation.BifurcationCurve"),
        "Contact-side": (lambda: ib.Contact(side="left"),
                         "Contact.side = 'left' is not allowed: must be one of"),
        "two_sided_stop-clearance_below": (lambda: ib.two_sided_stop(clearance_below=-1.0),
                                           "Contact.clearance = -1.0 is not allowed"),
        "first_contact-params": (lambda: ib.first_contact(None, 1.0), "params = None (NoneType) "
                                 "is not allowed: must be an impactbeams.Params"),
        "contact_sequence-t_max": (lambda: ib.contact_sequence(Params(), -1.0),
                                   "t_max = -1.0 is not allowed: must be > 0"),
        "plot_dataset-dataset": (lambda: ib.plot_dataset(5, "x.png"),
                                 "dataset = 5 (int) is not allowed: must be an xarray.Dataset"),
        "plot_dataset-dpi": (lambda: ib.plot_dataset(xr.Dataset(), "x.png", dpi=-1),
                             "dpi = -1"),
        "plot_dataset-events": (lambda: ib.plot_dataset(xr.Dataset(), "x.png", events="PD"),
                                "events = 'PD' is not allowed: 'PD' is not an event kind"),
    }


@pytest.mark.parametrize("name", sorted(_public_calls()))
def test_public_functions_check_their_arguments(name, monkeypatch):
    """One clear error, a TypeError or a ParameterError, naming the argument and its value;
    before any work (nothing computed, no file)."""
    monkeypatch.chdir(__import__("pathlib").Path(__file__).parents[1])
    call, fragment = _public_calls()[name]
    with pytest.raises((TypeError, ParameterError)) as error:
        call()
    assert fragment in str(error.value)
    assert isinstance(error.value, ParameterError)  # the command line reports it in one line


def test_the_public_functions_all_check_their_arguments():
    import impactbeams

    called = {name.split("-")[0].split(".")[0] for name in _public_calls()}
    functions = set(impactbeams.__all__) - {"ParameterError", "__version__"}
    assert functions <= called | {"write_sweep", "sweep_from_mapping"}, functions - called


def test_run_sweep_and_write_sweep_take_a_path(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(GOOD)
    from impactbeams.sweep import run_sweep, write_sweep

    expected = run_sweep(load_sweep(path))
    xr.testing.assert_identical(run_sweep(str(path)), expected)
    assert write_sweep(path, tmp_path / "tiny.nc") is True
    with xr.open_dataset(tmp_path / "tiny.nc") as written:
        np.testing.assert_array_equal(written.first_impact_time, expected.first_impact_time)


def test_numpy_scalars_in_a_sweep_mapping_are_python_numbers():
    """The definition is hashed as JSON: a NumPy scalar must not break the fingerprint."""
    sweep = sweep_from_mapping({"n_modes": np.int64(4), "params": {"clearance": np.float32(2e-5)},
                                "axes": {"omega": {"min": 50.0, "max": 60.0,
                                                   "num": np.int32(2)}}})
    assert sweep.fingerprint() == sweep_from_mapping({"n_modes": 4, "params": {
        "clearance": float(np.float32(2e-5))}, "axes": {"omega": {"min": 50.0, "max": 60.0,
                                                                  "num": 2}}}).fingerprint()


def test_the_largest_contact_damping_named_is_the_limit():
    """The refusal's "at most about C" is the threshold: C / 1.01 oscillates, 1.01 C does not
    (it is found to 0.1 % and printed to 3 digits)."""
    import re

    from impactbeams.compliant import spring_contact
    from impactbeams.model import build_free_phase

    params = Params(contact_stiffness=1e4, damping_ratio=0.01)
    free = build_free_phase(params, 8)

    def contact(damping):
        return spring_contact(free, params.tip_compliance, 0.01, 1e4, damping)

    with pytest.raises(ParameterError) as error:
        contact(1e6)
    limit = float(re.search(r"at most about (\S+) N s/m", str(error.value)).group(1))
    contact(limit / 1.01)
    with pytest.raises(ParameterError, match="contact_damping"):
        contact(limit * 1.01)


def test_a_stiff_contact_on_a_light_beam_has_its_modes():
    """A light beam 2 (modes to 4e11 rad/s): LAPACK's dlasd4 did not converge on the last
    contact root (a traceback in `modes`); solved again scaled, it agrees with a dense
    eigensolver to 1e-13 (the top root: dense solvers are accurate there)."""
    from impactbeams.compliant import rank_one_modes, recommended_modes, residual_flexibilities
    from impactbeams.model import build_free_phase

    params = Params(EI2=1e-3, rhoA2=2e-14)
    free = build_free_phase(params, recommended_modes(params))
    residual = sum(residual_flexibilities(free, params.tip_compliance))
    stiffness = params.contact_stiffness / (1 + params.contact_stiffness * residual)
    weights = free.tip1 - free.tip2
    frequencies, _ = rank_one_modes(free.frequencies, stiffness, weights)
    dense = np.sqrt(np.linalg.eigvalsh(np.diag(free.frequencies**2)
                                       + stiffness * np.outer(weights, weights)))
    assert frequencies[-1] == pytest.approx(dense[-1], rel=1e-13)


def test_one_mode_against_a_stop_has_its_contact_mode():
    """n_modes = 1 against a stop: one active weight, for which LAPACK's dlasd4 returns sigma
    alone (delta = work = 1), gave `math domain error`; the one contact frequency is
    sqrt(omega^2 + k w^2) exactly, and the run completes."""
    from impactbeams.contact.spring import rank_one_modes

    frequencies, modes = rank_one_modes(np.array([3.0]), 2.0, np.array([0.5]))
    assert frequencies[0] == pytest.approx(np.sqrt(9.5), rel=1e-15)
    assert abs(modes[0, 0]) == 1.0
    # two equal frequencies deflate to one active weight: the same path
    frequencies, modes = rank_one_modes(np.array([3.0, 3.0]), 2.0, np.array([0.5, 0.5]))
    dense = np.linalg.eigh(np.diag([9.0, 9.0]) + 2.0 * np.outer([0.5, 0.5], [0.5, 0.5]))
    assert frequencies == pytest.approx(np.sqrt(dense.eigenvalues), rel=1e-15)
    assert np.abs(modes.T @ dense.eigenvectors) == pytest.approx(np.eye(2), abs=1e-15)
    with pytest.warns(RuntimeWarning, match="n_modes = 1 does not resolve"):
        run = simulate(Params(counterpart="stop"), 0.012, n_modes=1)
    assert run.attrs["status"] == "complete"


STOP = Params(counterpart="stop", contact_law="tied")


@pytest.mark.parametrize(("state", "message"), [
    # a tip 233 km away ran with status complete
    (np.full(10, 1e3), "initial_state is not allowed: its free vibration deflects beam 1's tip "
                       "by up to 2.33e+05 m, more than 0.2 l1 = 0.02 m (small deflections"),
    # a velocity alone: its free vibration's amplitude q'/omega_n counts
    (np.r_[np.zeros(5), np.full(5, 1e3)], "deflects beam 1's tip by up to 239 m"),
    # passed with NumPy's ComplexWarning, the imaginary part dropped
    (np.full(10, 1e-6 + 1e-6j), "j]) is not allowed: complex; must be 10 finite numbers"),
])
def test_initial_states_beyond_the_model_are_refused_in_one_line(state, message):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no NumPy warning on the way
        with pytest.raises(ParameterError) as error:
            simulate(STOP, 0.01, n_modes=5, initial_state=state)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_an_initial_state_within_the_limit_is_taken():
    """A tip deflection of 4.7 mm (below 0.2 l1 = 20 mm) starts as given."""
    run = simulate(STOP, 0.01, n_modes=5, initial_state=np.r_[1e-4, np.zeros(9)],
                   times=np.array([0.0]))
    tip = float(build_free_phase(STOP, 5).tip1[0]) * 1e-4
    assert float(run.tip_deflection_1[0]) == pytest.approx(tip, rel=1e-12)


def test_beam_2_fields_against_a_stop_are_refused():
    from impactbeams.trajectory import InitialFields

    fields = InitialFields(deflection2=lambda x: 1e-6 * x)
    with pytest.raises(ParameterError, match="initial_state.deflection2 is not allowed: "
                                             "counterpart = 'stop' has no beam 2"):
        simulate(STOP, 0.01, n_modes=5, initial_state=fields)


@pytest.mark.parametrize("changes", [
    {}, {"counterpart": "stop", "shaker": "beam1", "base_amplitude": 1e-4, "force_amplitude": 0.0},
    {"contact_position1": 0.06, "contact_side": "above"},
    {"attachments1": [{"position": 0.05, "mass": 0.01}]},
])
def test_no_joint_rule_reads_what_replace_checks_alone(changes, monkeypatch):
    # Params.replace checks a change of UNJOINED parameters on its own, not with the joint
    # rules: those must not read them. With omega's value unreadable the joint rules still pass
    from impactbeams import params as module

    params = Params(**changes)
    monkeypatch.setattr(Params, "numeric", lambda self: {
        name: getattr(self, name) for name in self.numeric_names()
        if name not in module.UNJOINED})
    for name in module.UNJOINED:
        monkeypatch.setattr(Params, name, property(lambda self, name=name: pytest.fail(name)),
                            raising=False)
    params._check_together()
