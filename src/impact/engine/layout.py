"""Index constants of the engine's loops, one layout for both (plain ints: numba folds them).

The paper loop (paper_loop.py) runs one damper on one storey, so it reads the same vectors as the scene
loop, plus the five constants of its system (P_MU .. P_WP) after the scene's parameters; each loop fills
the diagnostics it has (the paper loop has no monitors and one unit, so no peak search, no simultaneous
impacts; the scene loop takes its amplitude from its monitors, not from D_X2WIN).
"""

# what a unit is made of (model.kinds), as bits of its kind: a mass between walls, held by a spring (and dashpot)
UNIT_WALLS, UNIT_SPRING = 1, 2

# unit modes
MODE_FREE = 0     # moving on its own (between the walls, or a TMD)
MODE_STUCK = 1    # resting against the wall on `side`, moving with its floor
MODE_LOCKED = 2   # gap d = 0: one body with its floor
MODE_FLOOR = 3    # friction only: dragged along by the floor away from the walls

# storey branches (a yielding building's storeys): elastic, or yielding with the drift growing (+1) or falling (-1)
BRANCH_ELASTIC = 0

# scalar parameters (float64 vector)
P_T0, P_TEND, P_TWIN, P_VSTICK, P_MAXEV, P_PERIOD = 0, 1, 2, 3, 4, 5
P_OMEGA, P_PHI, P_F0 = 6, 7, 8          # harmonic load F0 sin(Omega t + phi)
P_REC_T0, P_REC_DT = 9, 10              # record load: first sample time and step
P_WINDOW = 11  # the scene loop: 1.0 integrates the roof's square over the window (amplitude, RMS), 0.0 not (unread)
P_MAXEV_RUN = 12  # the run's event budget, its events in all (inf: none but the cap per period)
# the scene loop: 1.0 advances the state from itself on every segment, not only while a storey yields (a storey whose
# stability coefficient passes model.scene.MAX_STABILITY, in a scene the model refuses: segment.flow_change)
P_FROM_ITSELF = 13
NPAR = 14
# the paper loop's system, model units (M = 1, omega_n = 1): mass ratio, damping ratio, restitution, gap,
# the pendulum's tuning wp (0 for the CID)
P_MU, P_BETA, P_E, P_GAP, P_WP = range(NPAR, NPAR + 5)
NPAR_PAPER = NPAR + 5

# diagnostics (float64 vector)
D_IMPACTS, D_IMPACTS_WIN, D_STICKS, D_GRAZE, D_PEN = 0, 1, 2, 3, 4
D_WORK, D_VISC, D_IMPLOSS, D_E0, D_E1 = 5, 6, 7, 8, 9
D_CAP, D_NREC, D_STEPS, D_STUCKTIME, D_TEND = 10, 11, 12, 13, 14
D_FRICTION, D_SEGMENTS, D_SIMULTANEOUS, D_EMAX, D_PEAK_GAVE_UP = 15, 16, 17, 18, 19
D_X2WIN = 20  # the paper loop's integral of x^2 over the window (its amplitude)
# a yielding building's: the plastic work, the yield events, and whether a storey's drift passed its collapse limit
D_PLASTIC, D_YIELDS, D_COLLAPSE = 21, 22, 23
# a run stopped early (D_CAP: STOP_CAP, STOP_STALL or STOP_BUDGET): the element whose event it stopped at (a unit's index, or
# a storey's for a storey's event), that event's kind (EV_*) and its side (+1 / -1, 0 for none)
D_STOP_ELEMENT, D_STOP_EVENT, D_STOP_SIDE = 24, 25, 26
# the deepest penetration less the round-off of the positions it is read from (contact.note_penetration)
D_PEN_EXCESS = 27
D_CLEAR = 28  # segments taken as a whole record step by matrices (clear_step)
NDIAG = 29
# D_CAP: the cap on events per period, the stall guard (no progress), or the run's event budget
STOP_CAP, STOP_STALL, STOP_BUDGET = 1, 2, 3

# the events of the elements' table: a unit's (its walls, the end of a slide, the release from a wall, leaving the
# floor it rests on) and a storey's (the yield surface, its drift turning, the collapse limit); their names
EV_NONE, EV_WALL, EV_SLIDE_STOP, EV_RELEASE, EV_FLOOR_EXIT = 0, 1, 2, 3, 4
EV_YIELD, EV_UNLOAD, EV_COLLAPSE = 5, 6, 7
EVENT_NAMES = ("none", "wall", "slide stop", "release", "floor exit", "yield", "unload", "collapse")

# impact record columns: their names in order, and each one's index.  x: the displacement of the unit's
# floor; v, w: the floor's and the unit's velocities before (minus) and after (plus); stuck: whether the wall
# holds the unit after it; impulse: Newton's impulse of the wall on the unit (>= 0; the plastic end of a
# rebound too slow to resolve, contact.plastic_end, is not in it)
RECORD_COLUMNS = ("t", "unit", "side", "x", "v_minus", "w_minus", "v_plus", "w_plus", "stuck", "impulse")
R_T, R_UNIT, R_SIDE, R_X, R_V0, R_W0, R_V1, R_W1, R_STUCK, R_IMPULSE = range(len(RECORD_COLUMNS))
NREC = len(RECORD_COLUMNS)

# monitor kinds: a linear combination of positions, or of accelerations plus
# a multiple of the record (the absolute acceleration under ground motion)
MON_DISP, MON_ACCEL = 0, 1

NPOLY = 4  # polynomial part: degree 3 (a free mass under a piecewise-linear ground acceleration)
