"""The soft stop of tests/test_two_parameter.py with a second stop: the several contacts'
curves' models (tests/test_two_parameter_several.py, tests/test_grazing_several.py)."""

import impactbeams as ib
from impactbeams import Contact, two_sided_stop

# the shipped example's soft stop at the tip, 3 modes (tests/test_two_parameter.py's STOP)
STOP = ib.Params(counterpart="stop", contact_stiffness=100.0, damping_ratio=0.02,
                 force_amplitude=1e-4)
# the same stop with a stop above the tip 1 mm away, which the orbits (tips < 0.1 mm) never reach
FAR = STOP.replace(contacts=two_sided_stop(None, None, 1e-3))
# the tip stop and one 4 um below mid-span: both closed on the orbits from 210 rad/s up
TWO = STOP.replace(contacts=(Contact(clearance=1.1e-5), Contact(0.5 * STOP.l1, clearance=4e-6)))
N_MODES = 3
# TWO as a parameters file's tables
TWO_TOML = """[params]
counterpart = "stop"
contact_stiffness = 100.0
damping_ratio = 0.02
force_amplitude = 1e-4
[[params.contacts]]
clearance = 1.1e-5
[[params.contacts]]
position1 = 0.05
clearance = 4e-6
"""
