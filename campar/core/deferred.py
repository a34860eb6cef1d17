"""Extrema refined once a cell knows which revolutions it reports.

A cell stores the statistics of the revolutions of its verdict's window alone (the last
n of a cycle, the last window of a non-periodic motion: kernel.record_window), and its
verdict reads nothing of ε's and Pn's extremes (only section points, Jacobians and the
log-stretch). So the chain's revolutions do not refine an extremum on the dense output
while they run: a step whose models see one (extrema.step_models) folds only its end
values into the revolution's statistics and keeps what its refinement needs in the
revolution's row, after the statistics — its start, size, mode, the contact law's
impact velocity, the end values and rates, and the two state components of the step's
stages (or of its dense output, where the event search has prepared it already).
``refine_deferred`` redoes exactly what extrema.step_extremes would have done then, in
a work buffer of its own, for the window's revolutions only: the same numbers, on a
fraction of the steps.

A row of N_REV_STATS columns (shooting, the tracer) defers nothing; neither does a step
that finds its row's slots full: it is refined at once. Refining changes the order in
which interior extremes reach a row only then, which can matter only to REV_TOUCH
between two extremes of equal |ε|, and the chain reports no REV_TOUCH.
"""

from . import dop853, model
from .analysis import N_REV_STATS, add_step_stats
from .contact import impact_velocity, note_impact
from .extrema import step_extremes
from .integrator import CTRL_DENSE
from .jit import hot
from .model import N_STATE

DEFERRED = N_REV_STATS  # column of a chain's row: steps deferred so far in the revolution
SLOTS = 16  # steps a revolution defers at most (a revolution holds a few extrema)
KEPT_STAGES = dop853.N_STAGES + 1  # stage rows every method's dense output is built from

# A slot's columns.
T0 = 0
H = 1
MODE0 = 2
MODE1 = 3
FREE = 4
IMPACT = 5
ENDS = 6  # model.contact_kinematics at the step's start (5 numbers), then at its end
PREPARED = 16  # 1: the dense output's coefficients (dop853.INTERPOLATOR_POWER rows) follow
Y_OLD = 17
Y_NEW = Y_OLD + N_STATE
STAGES = Y_NEW + N_STATE  # KEPT_STAGES rows of N_STATE components (or the coefficients)
SLOT = STAGES + KEPT_STAGES * N_STATE

DEFER_COLUMNS = N_REV_STATS + 1 + SLOTS * SLOT  # width of a chain's statistics row


@hot
def clear_deferred(row):
    if row.shape[0] > N_REV_STATS:
        row[DEFERRED] = 0.0


@hot
def defer_step(row, w, t0, h, mode, free, impact, k0, k1):
    """Keep the step just accepted (its StepWork w: y_old, y_new, K, F, ctrl) for
    refine_deferred, with the kinematics k0, k1 at its ends (model.contact_kinematics);
    False when the row has no slot left (a row of N_REV_STATS columns has none)."""
    if row.shape[0] < DEFER_COLUMNS:
        return False
    count = int(row[DEFERRED])
    if count >= SLOTS:
        return False
    s = row[N_REV_STATS + 1 + count * SLOT : N_REV_STATS + 1 + (count + 1) * SLOT]
    s[T0] = t0
    s[H] = h
    s[MODE0] = mode[0]
    s[MODE1] = mode[1]
    s[FREE] = 1.0 if free else 0.0
    s[IMPACT] = impact
    for j, value in enumerate(k0):
        s[ENDS + j] = value
    for j, value in enumerate(k1):
        s[ENDS + len(k0) + j] = value
    for i in range(N_STATE):
        s[Y_OLD + i] = w.y_old[i]
        s[Y_NEW + i] = w.y_new[i]
    # the event search may have prepared the dense output already, from the integrator's
    # own step size: keep its coefficients, not a preparation from t0 and h
    prepared = w.ctrl[CTRL_DENSE] == 1.0
    s[PREPARED] = 1.0 if prepared else 0.0
    rows = dop853.INTERPOLATOR_POWER if prepared else KEPT_STAGES
    for r in range(rows):
        for i in range(N_STATE):
            s[STAGES + r * N_STATE + i] = w.F[r, i] if prepared else w.K[r, i]
    row[DEFERRED] = count + 1
    return True


@hot
def refine_deferred(row, w, mode, p, method, extremes):
    """Refine the steps the revolution of ``row`` deferred and fold their extremes into
    its statistics, in the steps' order (``extremes``: as extrema.step_extremes's); w
    (N_STATE components) and mode are scratch. The
    contact law's impact velocity is the step's while it is refined, then the cell's
    again."""
    if row.shape[0] < DEFER_COLUMNS:
        return
    count = int(row[DEFERRED])
    kept = impact_velocity(p.contact)
    for k in range(count):
        s = row[N_REV_STATS + 1 + k * SLOT : N_REV_STATS + 1 + (k + 1) * SLOT]
        mode[0] = int(s[MODE0])
        mode[1] = int(s[MODE1])
        note_impact(p.contact, s[IMPACT])
        for i in range(N_STATE):
            w.y_old[i] = s[Y_OLD + i]
            w.y_new[i] = s[Y_NEW + i]
        prepared = s[PREPARED] == 1.0
        rows = dop853.INTERPOLATOR_POWER if prepared else KEPT_STAGES
        for r in range(rows):
            for i in range(N_STATE):
                if prepared:
                    w.F[r, i] = s[STAGES + r * N_STATE + i]
                else:
                    w.K[r, i] = s[STAGES + r * N_STATE + i]
        w.ctrl[CTRL_DENSE] = 1.0 if prepared else 0.0
        k0 = (s[ENDS], s[ENDS + 1], s[ENDS + 2], s[ENDS + 3], s[ENDS + 4])
        k1 = (s[ENDS + 5], s[ENDS + 6], s[ENDS + 7], s[ENDS + 8], s[ENDS + 9])
        dip, peak, pn_hi = step_extremes(
            model.rhs, method, w, s[T0], s[H], p, mode, k0, k1, extremes
        )
        # the step's time and end values are in the row already (h 0 adds nothing)
        add_step_stats(row, 0.0, s[FREE] == 1.0, k0[0], k1[0], dip, peak, pn_hi)
    row[DEFERRED] = 0.0
    note_impact(p.contact, kept)
