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

``refine_window`` then refines, for the window's revolutions only, the extremes that can
be the window's: ε's lowest and highest, Pn's largest, and ε's dips near 0 (the grazing
flag). The models' values (extrema.step_model_extremes) rank the steps; a step is
refined where its model lies within a margin of the window's extreme, each refined
number being exactly what extrema.step_extremes gives. The margin starts at a fraction
of the window's range and grows to SAFETY times the largest model error the refined
steps showed, so a step left unrefined would need a model error fifteen times any this
window has shown to reach the extreme. The window's numbers are those of refining every
step (tests/test_deferred.py; 21 jobs and law variants compared byte for byte,
benchmarks/RESULTS.md); its rows hold the refined steps' interior extremes alone.

A row of N_REV_STATS columns (shooting, the tracer) defers nothing; neither does a step
that finds its row's slots full: it is refined at once. Refining changes the order in
which interior extremes reach a row only then, which can matter only to REV_TOUCH
between two extremes of equal |ε|, and the chain reports no REV_TOUCH.
"""

import math

from . import dop853, model
from .analysis import N_REV_STATS, REV_EPS_MAX, REV_EPS_MIN, REV_PN_MAX, add_step_stats
from .contact import impact_velocity, note_impact
from .extrema import refine_extremes, step_model_extremes
from .jit import hot
from .model import N_STATE
from .stages import CTRL_DENSE

DEFERRED = N_REV_STATS  # column of a chain's row: steps deferred so far in the revolution
SLOTS = 16  # steps a revolution defers at most (a revolution holds a few extrema)
# The margins a window's first round refines within: of its ε range and of its largest Pn.
# The quintic is off by ≤ 5e-4 of ε's range on the paper's planes, by up to 2 % with
# cycloidal laws (one long free-flight step); Pn's cubic by up to 3 % of the largest Pn.
# A window whose refined steps show more widens its margin (SAFETY) and refines again.
EPS_MARGIN = 0.01
PN_MARGIN = 0.02
SAFETY = 16.0  # a margin is at least this many times the largest error the window showed
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
MODEL_DIP = 17  # extrema.step_model_extremes of the step (refine_window's)
MODEL_PEAK = 18
MODEL_PN = 19
REFINED = 20  # bits: the step's dip, peak and Pn refined (DIP_DONE, PEAK_DONE, PN_DONE)
Y_OLD = 21
Y_NEW = Y_OLD + N_STATE
STAGES = Y_NEW + N_STATE  # KEPT_STAGES rows of N_STATE components (or the coefficients)
SLOT = STAGES + KEPT_STAGES * N_STATE

FIRST_SLOT = N_REV_STATS + 1
DEFER_COLUMNS = FIRST_SLOT + SLOTS * SLOT  # width of a chain's statistics row

DIP_DONE = 1
PEAK_DONE = 2
PN_DONE = 4


@hot
def clear_deferred(row):
    if row.shape[0] > N_REV_STATS:
        row[DEFERRED] = 0.0


@hot
def defer_step(row, y_old, y_new, stages, prepared, t0, h, mode, free, impact, k0, k1):
    """Keep the step just accepted (its states y_old, y_new and its ``stages``: the stage
    rows K, or the dense output's coefficients F where it is ``prepared``) for
    refine_window, with the kinematics k0, k1 at its ends (model.contact_kinematics);
    False when the row has no slot left (a row of N_REV_STATS columns has none)."""
    if row.shape[0] < DEFER_COLUMNS:
        return False
    count = int(row[DEFERRED])
    if count >= SLOTS:
        return False
    s = row[FIRST_SLOT + count * SLOT : FIRST_SLOT + (count + 1) * SLOT]
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
        s[Y_OLD + i] = y_old[i]
        s[Y_NEW + i] = y_new[i]
    s[PREPARED] = 1.0 if prepared else 0.0
    rows = dop853.INTERPOLATOR_POWER if prepared else KEPT_STAGES
    for r in range(rows):
        for i in range(N_STATE):
            s[STAGES + r * N_STATE + i] = stages[r, i]
    row[DEFERRED] = count + 1
    return True


@hot
def slot_ends(s):
    """model.contact_kinematics at the kept step's start and end."""
    k0 = (s[ENDS], s[ENDS + 1], s[ENDS + 2], s[ENDS + 3], s[ENDS + 4])
    k1 = (s[ENDS + 5], s[ENDS + 6], s[ENDS + 7], s[ENDS + 8], s[ENDS + 9])
    return k0, k1


@hot
def refine_slot(row, s, w, mode, p, method, want_dip, want_peak, want_pn):
    """Refine the kept step ``s`` of ``row`` (the quantities wanted: extrema.refine_extremes)
    in w and fold what it finds into the row's statistics; returns the refined numbers.
    The contact law's impact velocity is left at the step's."""
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
    k0, k1 = slot_ends(s)
    dip, peak, pn_hi = refine_extremes(
        model.rhs, method, w, s[T0], s[H], p, mode, k0, k1, want_dip, want_peak, want_pn
    )
    # the step's time and end values are in the row already (h 0 adds nothing)
    add_step_stats(row, 0.0, s[FREE] == 1.0, k0[0], k1[0], dip, peak, pn_hi)
    return dip, peak, pn_hi


@hot
def refine_window(revs, first, count, w, mode, p, method, extremes, graze_tol):
    """Refine the steps revolutions first … first+count−1 of ``revs`` deferred whose
    extremes can be the window's (ε's lowest, ε's dips within ``graze_tol`` of 0, and with
    ``extremes`` ε's highest and Pn's largest), folding them into the revolutions'
    statistics; w (N_STATE components) and mode are scratch. The window's extremes are
    those of refining every step (the module's docstring says why)."""
    if revs.shape[1] < DEFER_COLUMNS:
        return
    kept = impact_velocity(p.contact)
    lo = math.inf
    hi = -math.inf
    top = 0.0
    for j in range(first, first + count):
        row = revs[j]
        lo = min(lo, row[REV_EPS_MIN])
        hi = max(hi, row[REV_EPS_MAX])
        top = max(top, row[REV_PN_MAX])
        for k in range(int(row[DEFERRED])):
            s = row[FIRST_SLOT + k * SLOT : FIRST_SLOT + (k + 1) * SLOT]
            mode[0] = int(s[MODE0])
            mode[1] = int(s[MODE1])
            k0, k1 = slot_ends(s)
            dip, peak, pn_hi = step_model_extremes(s[H], mode, k0, k1, extremes)
            if s[FREE] == 1.0:
                pn_hi = math.nan  # a separated step's Pn counts for nothing
            s[MODEL_DIP] = dip
            s[MODEL_PEAK] = peak
            s[MODEL_PN] = pn_hi
            s[REFINED] = 0.0
            if dip == dip:
                lo = min(lo, dip)
            if peak == peak:
                hi = max(hi, peak)
            if pn_hi == pn_hi:
                top = max(top, pn_hi)
    eps_margin = EPS_MARGIN * (hi - lo)
    pn_margin = PN_MARGIN * top
    eps_error = 0.0
    pn_error = 0.0
    while True:
        for j in range(first, first + count):
            row = revs[j]
            for k in range(int(row[DEFERRED])):
                s = row[FIRST_SLOT + k * SLOT : FIRST_SLOT + (k + 1) * SLOT]
                done = int(s[REFINED])
                dip_m = s[MODEL_DIP]
                peak_m = s[MODEL_PEAK]
                pn_m = s[MODEL_PN]
                want_dip = (
                    dip_m == dip_m
                    and not done & DIP_DONE
                    and (dip_m <= lo + eps_margin or abs(dip_m) <= graze_tol + eps_margin)
                )
                want_peak = peak_m == peak_m and not done & PEAK_DONE and peak_m >= hi - eps_margin
                want_pn = pn_m == pn_m and not done & PN_DONE and pn_m >= top - pn_margin
                if not (want_dip or want_peak or want_pn):
                    continue
                dip, peak, pn_hi = refine_slot(
                    row, s, w, mode, p, method, want_dip, want_peak, want_pn
                )
                if want_dip:
                    eps_error = max(eps_error, abs(dip - dip_m))
                    done |= DIP_DONE
                if want_peak:
                    eps_error = max(eps_error, abs(peak - peak_m))
                    done |= PEAK_DONE
                if want_pn:
                    pn_error = max(pn_error, abs(pn_hi - pn_m))
                    done |= PN_DONE
                s[REFINED] = done
        grown = False
        if SAFETY * eps_error > eps_margin:
            eps_margin = 2.0 * SAFETY * eps_error
            grown = True
        if SAFETY * pn_error > pn_margin:
            pn_margin = 2.0 * SAFETY * pn_error
            grown = True
        if not grown:
            break
    for j in range(first, first + count):
        revs[j, DEFERRED] = 0.0
    note_impact(p.contact, kept)
