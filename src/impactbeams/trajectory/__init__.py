"""Full impact dynamics of the two beams: one trajectory as an xarray Dataset.

The data flow, one module each: `impactbeams.packing` packs the modal model into plain
arrays; `phases` runs the event-driven kernel
(`impactbeams.kernels.dynamics`) and samples the recorded phase segments;
`observables` evaluates tips, gap, force and energies from the
exact segment states; `fields` (time series, deflection surfaces)
and `impacts` (the per-impact table) reduce them;
`simulation` holds [`simulate`][] and builds the Dataset; `several` the first contact among
several (`impactbeams.Params.contacts`) and the contacts of a two-sided stop.
"""

from impactbeams.packing import Packed, pack_run
from impactbeams.trajectory.observables import observables
from impactbeams.trajectory.phases import Trajectory, run, sample
from impactbeams.trajectory.several import FirstContact, contact_sequence, first_contact
from impactbeams.trajectory.simulation import simulate
from impactbeams.trajectory.start import InitialFields

__all__ = ["FirstContact", "InitialFields", "Packed", "Trajectory", "contact_sequence",
           "first_contact", "observables", "pack_run", "run", "sample", "simulate"]
