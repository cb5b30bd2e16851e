"""The named bundles in which the scene loop passes its arrays.

numba compiles a namedtuple into a struct, and a compiled function takes a few
bundles instead of dozens of positional arrays.  The steps the loop runs on every
segment (scene_loop.search_constraints, monitor_modal, integrate_energy, move_to_end,
modal.integrate_modal, ...) are compiled calls, and each array in a call's
arguments costs a reference count, a namedtuple as many as it holds (bundling
them in namedtuples cost 8 to 31 % of a run on benchmarks/bench_scene.py's
cases): they take one SegmentWork, a structref, which counts only the fields a
step reads.

The optional parts of a scene (`springs`: PID and TMD units, `fric`: Coulomb
friction, `harm`: a harmonic load, `record`: a load record) are not in a
bundle: each travels as its own argument, None when the scene lacks it.
numba prunes a branch on `arg is None` only for a function's own argument, and
that pruning is what makes a scene compile only the code it uses.
"""

from __future__ import annotations

from collections import namedtuple

from numba import types
from numba.core import cgutils
from numba.experimental import structref
from numba.extending import intrinsic

#: the storeys: floor masses, storey stiffness and damping matrices
BuildingArrays = namedtuple("BuildingArrays", "mass stiffness damping")

#: one entry per damper unit: kind (what it is made of, layout.UNIT_* bits), floor index, mass, load per unit mass, gap, restitution
UnitArrays = namedtuple("UnitArrays", "kind floor mass load gap restitution")

#: the units' spring stiffness and dashpot (zero for a CID unit); absent when every unit is a CID
SpringArrays = namedtuple("SpringArrays", "stiffness damping")

#: the storeys of a building that yields (absent for an elastic one), one entry per storey: the yield law of
#: its rows in the constraint table (Events).  Its law: elastic stiffness k, hardening ratio b, yield drift d_y,
#: P-delta's geometric stiffness P/h and the drift |u| at which the run stops as a collapse.  Its state, which
#: the run advances and leaves as its result: the branch (layout.BRANCH_ELASTIC, or +1 / -1 yielding), the
#: perfectly plastic element's offset p, the escape flags of its drift and drift-velocity searches, its plastic
#: work and its yield events
YieldArrays = namedtuple("YieldArrays", "stiffness hardening yield_drift geometric limit branch offset escape escape_v "
                                        "plastic yields")

#: a whole record step by matrices (clear_step.clear_step_tables), every unit free, for each pattern of the storeys'
#: branches it is made for (masks: the yielding storeys' bits, 0 first), each array the patterns' rows stacked: the
#: state's flow over (q, q', f(0), f', p), the quadratic forms of the load's work, the viscous dissipation and the
#: roof's square over the step, the particular motion at the step's start, the rows reading the modal amplitudes
#: of the state less it (one of each complex pair) and their sizes; then a table of rows (each monitor, each
#: monitor's slope, each band: a walled unit's gap, then each storey's drift; each storey's drift velocity): each
#: row over the state (ends), the rows bounding its second derivative (bound: over |state less particular|, then
#: over the modal amplitudes' moduli) and the load's part of that bound (load); then, for every pattern, each walled
#: unit's half gap and each degree of freedom's twin (the same unit before it, or -1)
ClearStep = namedtuple("ClearStep", "masks flow work visc square part inv inv_size ends bound load half twin")

#: what the run certifies peaks of: rows over the degrees of freedom, kind (layout.MON_*),
#: the record's coefficient (an absolute acceleration), a cap the peak cannot pass, and the first monitor of the
#: group whose running peak it shares (itself where its own peak is certified; events.raise_peak)
MonitorArrays = namedtuple("MonitorArrays", "rows kind record_coef cap share")

#: the paper loop's workspace (paper_loop._loop, every array borrowed): its complex rows over the seven slots (the
#: exponents kap, x's and y's coefficients cx cy, the gap row cs, the velocity row cv, a contact row cq, the force
#: row cf, exp(kap tau) eh, |kap|^n kpow and the exponents it was made for), the polynomial parts (poly; pp as the
#: search takes it), the searches' outputs (ev, ev2), the contact state c (a ContactState), the run's parameters
#: p, its state z, diagnostics and impact records
#: one call of the paper loop for its dense output (sampler.paper_samples): its parameters, the PID's eigen-data, and
#: where it writes (impact records, diagnostics, the final state)
PaperCall = namedtuple("PaperCall", "p pid rec diag z_out")

#: the paper loop's one unit's contact state, as the scene loop's RunState holds every unit's (arrays of one): mode
#: (layout.MODE_*), wall side (+-1, 0), slide sign sigma (+-1, 0), and the escapes of the next segment's gap and slide
#: searches (the boundary each starts on and leaves); contact.py's transitions set it
ContactState = namedtuple("ContactState", "mode side sigma escape escape_v")

PaperWork = namedtuple("PaperWork", "kap cx cy cs cv cq cf eh kpow kap_powered poly pp ev ev2 c p z diag rec")

#: the scene's arrays that every run has: parameters (layout.P_*), building, units, load vector, monitors
SceneArrays = namedtuple("SceneArrays", "p building units load_vec monitors")

#: where a run starts: positions, velocities, and each unit's contact mode and wall side
StartState = namedtuple("StartState", "q v mode side")

#: what a run writes: impact records (layout.R_*), diagnostics (layout.D_*), final state, each monitor's
#: peak, its time, the window's square integral and the round-off its peak is certified to (events.peak_abs's
#: slack, the largest of the run), the dense output at the times ts, and every unit's final contact state (a row
#: of mode, wall side and slide sign)
RunOutputs = namedtuple("RunOutputs", "recs diag q v peak peak_t x2 roundoff ts samples contact")

#: the state the loop advances: every unit's contact state (mode, wall side, slide sign, offset from its
#: floor, escape flags of the event searches, what settle checks), positions and velocities
RunState = namedtuple("RunState", "mode side sigma offset escape escape_v check q v")

#: eigen-data of configurations, one slot each (segment.config_slot): configuration key, reduced size,
#: eigenvalues, eigenvectors and inverse, K^-1, reduced damping, full index of each reduced
#: degree of freedom, reduced load, the harmonic particular solution per unit load, and the reduced masses
ConfigCache = namedtuple("ConfigCache", "key size lam vec vinv kinv damping dof load forced mass")

#: per-slot modal tables (modal.modal_slot): key, viscous quadratic form, the load's work per mode,
#: each monitor's modal coefficients and curvature bound, and each yielding storey's reach (modal.storey_reach)
ModalTables = namedtuple("ModalTables", "key gvis lmod mvec mbnd reach")

#: a record's whole sample step per slot (scene_loop.step_tables): key, exp(kap dt), integral tables (the ramp
#: form's too: segment.ramp_tables)
StepTables = namedtuple("StepTables", "key ek pair single ramp")

#: a segment in coefficient form (rows C, P over the exponents kap) with exp(kap tau), the integral
#: tables over tau (single's columns: segment.SINGLE_COLUMNS; ramp: segment.ramp_tables) and |kap|^n
Segment = namedtuple("Segment", "kap C P ek pair single ramp kpow")

#: scratch rows: gap and contact rows (cs ps, cq pq), a monitor's row (cm pm), velocity rows (cv pv),
#: and two work rows (cu pu)
Rows = namedtuple("Rows", "cs ps cq pq cm pm cv pv cu pu")

#: scratch vectors: the peak search's stack, an event search's output, the dense output's state, the
#: velocities before an impact, reduced-size scratch, |modal amplitudes|, the units' offsets before a
#: segment, and the weights of the half rows (modal.mode_weights)
Vectors = namedtuple("Vectors", "stack found qs vs v_before reduced moduli s_before wt")

#: the constraint table's events on a segment: per row, the next event's time, side and kind (layout.EV_*).
#: A row is a difference of two degrees of freedom with a band it must stay in (or its velocity or its contact
#: force, by the element's branch): every damper unit's row (the unit less its floor: its walls, its slide, its
#: release), then every yielding storey's (its floor less the one below: its yield surface, its unloading, its
#: collapse limit).  Beside them, per unit, what an instant's impacts did and its scratch flags (units resting on
#: a wall they touched, floors whose impacts are done), and a floor's impacts' scratch (scene_loop.impacts_on_floor:
#: each unit's group, and per group its approach speed, inverse mass, side, restitution, count and impulse), so that
#: an impact allocates nothing
Events = namedtuple("Events", "t side kind hit impulse touched floors_done group contacts")

#: tables kept across segments: modal tables, a record step's tables, build_segment's scratch
#: (floats, complexes) and the cache slot to replace next
Tables = namedtuple("Tables", "modal step work cursor")

#: the whole workspace of a run, allocated once
Workspace = namedtuple("Workspace", "seg rows vecs events tables")

#: what the steps at an event's instant (resolve_events, settle, _record_impacts) work in beside the run's
#: state: the per-segment steps' SegmentWork (settle builds segments and contact rows in it), the cache's
#: cursor, the events and the velocities before them, and the run's impact records and diagnostics.  These
#: steps are compiled calls, not inlined, and each array of their arguments is copied in on every event
InstantScratch = namedtuple("InstantScratch", "seg_work cursor events v_before recs diag")


#: the arrays of the cache (ConfigCache's fields but key), the modal tables (ModalTables' but key) and the
#: scratch (work's floats and complexes), each a field of SegmentWork of its own.  Reading a namedtuple out of a
#: structref counts a reference for every array it holds and its fields again: reading w.cache.lam counts twelve
#: where w.lam counts one.  The steps on every segment read these; w.cache stays whole for has_rigid_mode and
#: settle, which take the bundle
FLAT_FIELDS = "size lam vec vinv kinv damping dof load forced mass gvis lmod mvec mbnd reach wf wc"


@structref.register
class SegmentWorkType(types.StructRef):
    def preprocess_fields(self, fields):
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class SegmentWork(structref.StructRefProxy):
    """The arrays the steps on every segment work in, as one numba structref (built in run_scene).

    A structref travels as one reference, and a step counts a reference only for each field it reads; a
    namedtuple counts one for every array it holds, which made bundling these steps cost 8 to 31 %.  The
    fields: the segment (kap C P ek pair single ramp kpow), the scratch rows (Rows), the vectors the steps use
    (the peak search's stack, an event search's output, reduced-size scratch cu1, |modal amplitudes| aw,
    offsets before the segment, mode weights wt), each constraint row's next event (ev_t ev_side ev_kind),
    build_segment's scratch, the modal tables, the configuration cache, the load vector, the run's state
    (RunState's arrays but check), and what the segment writes (diagnostics, the monitors' peaks,
    their times, the window's square, the round-off each peak is certified to).  Its arrays are borrowed views
    (borrowed): `owner` holds what they are views of, for as long as the SegmentWork lives.
    """


SEGMENT_WORK_FIELDS = ("kap C P ek pair single ramp kpow cs ps cq pq cm pm cv pv cu pu stack found cu1 aw s_before wt "
                       "ev_t ev_side ev_kind cache load_vec mode side sigma offset escape escape_v q v "
                       "diag mon_peak mon_peak_t mon_x2 mon_roundoff " + FLAT_FIELDS + " owner").split()
structref.define_proxy(SegmentWork, SegmentWorkType, SEGMENT_WORK_FIELDS)



def _borrowable(typ):
    """Whether `borrowed` takes this type: an array, None, a number, or a tuple (named or not) of these."""
    if isinstance(typ, types.BaseTuple):
        return all(_borrowable(t) for t in typ.types)
    return isinstance(typ, (types.Array, types.NoneType, types.Number, types.Boolean))


def _borrow_value(context, builder, typ, value):
    """The value with every array in it replaced by a view without a meminfo (tuples rebuilt as their own type)."""
    if isinstance(typ, types.BaseTuple):
        parts = [_borrow_value(context, builder, t, builder.extract_value(value, i)) for i, t in enumerate(typ.types)]
        return context.make_tuple(builder, typ, parts)
    if not isinstance(typ, types.Array):
        return value  # None or a number: nothing counted
    src = context.make_array(typ)(context, builder, value=value)
    out = context.make_array(typ)(context, builder)
    out.meminfo = cgutils.get_null_value(out.meminfo.type)
    out.parent = cgutils.get_null_value(out.parent.type)
    out.nitems = src.nitems
    out.itemsize = src.itemsize
    out.data = src.data
    out.shape = src.shape
    out.strides = src.strides
    return out._getvalue()


@intrinsic
def borrowed(typingctx, arr):
    """A view of the array that holds no reference to its memory: the same data, shape and strides, no meminfo;
    of a bundle (a namedtuple or tuple of arrays, nested or not), the same bundle of such views; of None, None.

    numba counts a reference, atomically, each time a step reads an array out of a structref or binds one to a
    step's argument, and its pruning pass removes only the counts it can pair within simple blocks: on a
    bare building those counts were 75 % of the scene loop's time (about 130 pairs per segment, found with
    gdb on NRT_incref).  A borrowed view's counts test a null pointer and return.  It is safe while its owner
    lives: numba frees an array after its owner's last use, not at the end of the function, so whatever holds
    borrowed views holds their owner too (SegmentWork's `owner`: the run's workspace, state and clear-step
    scratch, which no step reads), or borrows from the function's arguments, which its caller holds.  An
    optional part of a scene (None when the scene lacks it) is borrowed by the same call, and stays None.
    """
    if not _borrowable(arr):
        return None

    def codegen(context, builder, sig, args):
        return _borrow_value(context, builder, arr, args[0])

    return arr(arr), codegen
