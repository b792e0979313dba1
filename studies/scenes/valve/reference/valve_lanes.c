/* C reference of the valve lane kernel, for the speed comparison in `python -m studies bench
 * valve` (issue "Valve train": "a C -O3 kernel of this form"). Never used in studies.
 *
 * The same work as engine_kernels/valvetrain/valve/lanes.py with one RK4 sub-step per grid step: model
 * [V2] per unit mass, classic RK4 over the cam-angle grid from a shared excitation table,
 * branch-free contact switches, and the same running observations (extremes, jump, seat
 * phase, bounces, mode transitions, energy balance every ENERGY_INTERVAL grid points; maxima,
 * jump start and seating velocity located between grid points as in located.py) and outputs.
 * The table may hold the lift before the lash take-up: every read clips it (clip_lift). Cases run in blocks of LANES in `omp simd` loops, blocks in an `omp parallel for`;
 * `valve_one_case` runs the same code one case at a time (one lane per block). REAL is the
 * precision of the lanes (double or float, set when compiling); coefficients are computed in
 * double, as in the Numba kernel. No stability guard and no parameter validation: the bench
 * only passes cases the guard integrates with one sub-step. SPEC §4.
 */
#include <math.h>
#include <string.h>

#ifndef REAL
#define REAL double
#endif
#define LANES 32
#define ENERGY_INTERVAL 8
#define ENERGY_SLACK 0.05
#define ENERGY_REST_RISE 0.25
#define ENERGY_FLOOR_FRACTION 1e-3
#define TRANSITION_BAND 1e-6
#define SEATING_NEWTON_TOLERANCE 1e-12
#define MAX_SEATING_ITERATIONS 50

enum { P_SPEED, P_MASS, P_DRIVE_STIFFNESS, P_DRIVE_DAMPING, P_SPRING_RATE, P_PRELOAD,
       P_SEAT_STIFFNESS, P_SEAT_DAMPING, P_EXTERNAL_DAMPING, P_INITIAL_LIFT,
       P_INITIAL_VELOCITY, N_PARAMS };
enum { O_MAX_LIFT, O_MAX_VELOCITY, O_MIN_VELOCITY, O_MAX_ACCELERATION, O_MIN_ACCELERATION,
       O_JUMP_START, O_JUMP_DURATION, O_JUMP_GAP, O_BOUNCE_COUNT, O_BOUNCE_HEIGHT,
       O_SEATING_VELOCITY, O_MAX_CONTACT_FORCE, O_SUBSTEPS, O_STEP_RATIO, O_TRANSITIONS,
       O_STATUS, O_ERROR_ESTIMATE, N_OUT };
enum { SEATED, OPEN, CLOSED, BOUNCING };

typedef struct {
    REAL k[LANES], b[LANES], ks[LANES], ps0[LANES], kz[LANES], bz[LANES], gamma[LANES];
    REAL depth[LANES], speed[LANES], b_speed[LANES], band[LANES], mass[LANES];
    REAL tau[LANES], half_tau[LANES], sixth_tau[LANES], time_step[LANES];
    REAL y[LANES], v[LANES], acc[LANES], prev_y[LANES], prev_v[LANES];
    REAL max_lift[LANES], max_v[LANES], min_v[LANES], max_a[LANES], min_a[LANES];
    REAL max_force[LANES], jump_start[LANES], jump_steps[LANES], jump_gap[LANES];
    REAL phase[LANES], bounce_height[LANES], contact[LANES], seated[LANES];
    REAL transitions[LANES], power_sum[LANES], power_first[LANES];
    REAL seat_y0[LANES], seat_v0[LANES], seat_a0[LANES], captured[LANES];
    REAL bounces[LANES], energy0[LANES], excess[LANES], work_max[LANES];
    REAL rest_energy[LANES], rest_rise[LANES];
    REAL point_angle[LANES], point_y[LANES], point_v[LANES], point_drive[LANES];
    REAL inv_speed[LANES], seat_j0[LANES];
} Block;

static inline REAL pos(REAL x) { return x > 0 ? x : 0; }
static inline REAL larger(REAL a, REAL b) { return b > a ? b : a; }
static inline REAL smaller(REAL a, REAL b) { return b < a ? b : a; }
/* the excitation the valve feels: zero until the lash is taken up */
static inline REAL clip_lift(REAL y) { return y > 0 ? y : 0; }
static inline REAL clip_slope(REAL y, REAL slope) { return y > 0 ? slope : 0; }

static inline REAL acceleration(const Block *s, int l, REAL y, REAL v, REAL push,
                                REAL *drive, REAL *seat) {
    *drive = push - s->k[l] * y - s->b[l] * v;
    *seat = s->ps0[l] - s->kz[l] * y - s->bz[l] * v;
    REAL seat_force = y < s->depth[l] ? pos(*seat) : 0;
    return (pos(*drive) + seat_force) - (s->ps0[l] + s->ks[l] * y + s->gamma[l] * v);
}

static inline REAL energy(const Block *s, int l, REAL y, REAL v, REAL drive_lift) {
    REAL seat = y < s->depth[l] ? s->depth[l] - y : 0;
    REAL drive = drive_lift > y ? drive_lift - y : 0;
    return (REAL)0.5 * v * v + (REAL)0.5 * s->ks[l] * y * y + s->ps0[l] * y
           + (REAL)0.5 * s->kz[l] * (seat * seat - s->depth[l] * s->depth[l])
           + (REAL)0.5 * s->k[l] * drive * drive;
}

/* Running observations at a grid point (the first one starts them); returns 1 if the seat
 * phase changed (first closure, a bounce), so record_events must run. */
static inline int observe(Block *s, int l, REAL angle, REAL y, REAL v, REAL a,
                          REAL drive_lift, REAL drive_velocity, REAL drive, REAL seat,
                          int first, int past_nose) {
    REAL depth = s->depth[l], band = s->band[l];
    if (first) {
        s->phase[l] = y > depth ? OPEN : SEATED;
        s->contact[l] = drive > 0;
        s->seated[l] = (y < depth ? seat : -INFINITY) > 0;
        s->power_sum[l] = s->power_first[l] = pos(drive) * drive_velocity;
    }
    s->max_lift[l] = larger(s->max_lift[l], y);
    s->max_v[l] = larger(s->max_v[l], v);
    s->min_v[l] = smaller(s->min_v[l], v);
    s->max_a[l] = larger(s->max_a[l], a);
    s->min_a[l] = smaller(s->min_a[l], a);
    s->max_force[l] = larger(s->max_force[l], drive);
    REAL phase = s->phase[l];
    REAL y0 = s->point_y[l], v0 = s->point_v[l], f0 = s->point_drive[l];
    REAL previous_angle = s->point_angle[l];
    if (!first) { /* the lift's maximum between the previous grid point and this one */
        REAL span = (angle - previous_angle) * s->inv_speed[l];
        int turning = (v0 > 0) & (v <= 0);
        REAL f = turning ? v0 / (v0 - v) : 0, f2 = f * f, f3 = f2 * f;
        REAL peak = (2 * f3 - 3 * f2 + 1) * y0 + (f3 - 2 * f2 + f) * span * v0
                    + (3 * f2 - 2 * f3) * y + (f3 - f2) * span * v;
        peak = turning ? larger(peak, y) : y;
        s->max_lift[l] = larger(s->max_lift[l], peak);
        int bounced = phase >= CLOSED;
        s->bounce_height[l] = larger(s->bounce_height[l], bounced & (peak > depth) ? peak - depth : 0);
    }
    int crossing = (f0 >= 0) & (f0 > drive);
    REAL fraction = crossing ? f0 / (f0 - drive) : 1;
    REAL start = first ? angle : previous_angle + fraction * (angle - previous_angle);
    int off_seat = y > depth;
    int separated = off_seat & (drive <= 0) & (phase < CLOSED);
    s->jump_start[l] = smaller(s->jump_start[l], separated ? start : INFINITY);
    s->jump_steps[l] += separated ? 1 : 0;
    s->jump_gap[l] = larger(s->jump_gap[l], separated ? y - drive_lift : 0);
    s->point_angle[l] = angle;
    s->point_y[l] = y;
    s->point_v[l] = v;
    s->point_drive[l] = drive;
    if (first) return 0;
    int closed = phase >= CLOSED;
    int closing = (phase == OPEN) & !off_seat & past_nose;
    REAL on_seat_phase = closed | closing ? CLOSED : SEATED;
    s->phase[l] = off_seat ? (closed ? BOUNCING : OPEN) : on_seat_phase;
    s->bounce_height[l] = larger(s->bounce_height[l], off_seat & closed ? y - depth : 0);
    REAL previous = s->contact[l], before = s->seated[l];
    REAL contact = drive >= -band ? previous : 0;
    contact = drive > band ? 1 : contact;
    REAL seat_mode = y < depth ? seat : -INFINITY;
    REAL seated = seat_mode >= -band ? before : 0;
    seated = seat_mode > band ? 1 : seated;
    s->transitions[l] += fabs(contact - previous) + fabs(seated - before);
    s->contact[l] = contact;
    s->seated[l] = seated;
    s->power_sum[l] += pos(drive) * drive_velocity;
    return closing | ((phase == CLOSED) & off_seat);
}

/* prev_drive_lift, prev_slope, prev_curvature: clipped excitation Y, Y', Y'' at the previous
 * grid point (state prev_y, prev_v). */
static inline void record_events(Block *s, int l, REAL prev_drive_lift, REAL prev_slope,
                                 REAL prev_curvature) {
    REAL phase = s->phase[l];
    if (phase >= CLOSED && s->captured[l] == 0) {
        REAL drive, seat;
        REAL push = s->k[l] * prev_drive_lift + s->b_speed[l] * prev_slope;
        REAL y = s->prev_y[l], v = s->prev_v[l];
        REAL a = acceleration(s, l, y, v, push, &drive, &seat);
        REAL speed = s->speed[l];
        REAL rate = s->k[l] * (speed * prev_slope - v) + s->b[l] * (speed * speed * prev_curvature - a);
        s->seat_y0[l] = y;
        s->seat_v0[l] = v;
        s->seat_a0[l] = a;
        s->seat_j0[l] = -(s->ks[l] * v + s->gamma[l] * a) + (drive > 0 ? rate : 0);
        s->captured[l] = 1;
    }
    if (phase == BOUNCING && !(s->prev_y[l] > s->depth[l])) s->bounces[l] += 1;
}

static inline void observe_energy(Block *s, int l, REAL y, REAL v, REAL drive_lift,
                                  REAL drive_velocity, REAL drive) {
    REAL e = energy(s, l, y, v, drive_lift);
    REAL initial = isnan(s->energy0[l]) ? e : s->energy0[l];
    s->energy0[l] = initial;
    REAL power = pos(drive) * drive_velocity;
    REAL work = (REAL)0.5 * s->time_step[l] * (2 * s->power_sum[l] - s->power_first[l] - power);
    s->excess[l] = larger(s->excess[l], e - initial - work);
    s->work_max[l] = larger(s->work_max[l], fabs(work));
    int resting = (s->phase[l] >= CLOSED) & (drive_lift == 0) & (drive_velocity == 0);
    REAL before = s->rest_energy[l];
    REAL rise = e - (1 + (REAL)ENERGY_REST_RISE) * before;
    s->rest_rise[l] = larger(s->rest_rise[l], resting & !isnan(before) ? rise : -INFINITY);
    s->rest_energy[l] = resting ? e : NAN;
}

/* Speed at the seat plane from `height` above it along the cubic Taylor polynomial of the
 * motion (seating_speed of located.py). */
static double seating_speed(double height, double v, double a, double j) {
    double squared = v * v - 2.0 * a * height;
    double fallback = sqrt(squared > 0 ? squared : 0);
    if (!(v < 0 && squared > 0 && height >= 0)) return fallback;
    double tau = 2.0 * height / (-v + fallback);
    for (int i = 0; i < MAX_SEATING_ITERATIONS; i++) {
        double rate = v + tau * (a + 0.5 * tau * j);
        if (!(rate < 0)) return fallback;
        double value = height + tau * (v + tau * (0.5 * a + tau * j / 6.0));
        double change = value / rate;
        tau -= change;
        if (fabs(change) <= SEATING_NEWTON_TOLERANCE * tau) break;
    }
    double rate = v + tau * (a + 0.5 * tau * j);
    if (!(tau >= 0 && rate < 0)) return fallback;
    return -rate;
}

static inline void finish(const Block *s, int l, double step_angle, double *out) {
    for (int i = 0; i < N_OUT; i++) out[i] = NAN;
    out[O_MAX_LIFT] = s->max_lift[l];
    out[O_MAX_VELOCITY] = s->max_v[l];
    out[O_MIN_VELOCITY] = s->min_v[l];
    out[O_MAX_ACCELERATION] = s->max_a[l];
    out[O_MIN_ACCELERATION] = s->min_a[l];
    out[O_JUMP_START] = s->jump_start[l] < INFINITY ? s->jump_start[l] : NAN;
    out[O_JUMP_DURATION] = s->jump_steps[l] * step_angle;
    out[O_JUMP_GAP] = s->jump_gap[l];
    out[O_BOUNCE_COUNT] = s->bounces[l];
    out[O_BOUNCE_HEIGHT] = s->bounce_height[l];
    /* unknown where the valve had not settled when the window ended (settling_energy) */
    REAL y = s->y[l], v = s->v[l], depth = s->depth[l];
    REAL settling = (REAL)0.5 * v * v + s->ps0[l] * (y - depth);
    if (y < depth) settling += (REAL)0.5 * s->kz[l] * (depth - y) * (depth - y);
    if (y < 0) settling += (REAL)0.5 * s->k[l] * y * y;
    if (settling > 0) out[O_BOUNCE_COUNT] = NAN;
    if (settling > s->ps0[l] * out[O_BOUNCE_HEIGHT]) out[O_BOUNCE_HEIGHT] = NAN;
    if (s->captured[l] == 1)
        out[O_SEATING_VELOCITY] = seating_speed(s->seat_y0[l] - s->depth[l], s->seat_v0[l],
                                                s->seat_a0[l], s->seat_j0[l]);
    out[O_MAX_CONTACT_FORCE] = s->mass[l] * s->max_force[l];
    out[O_SUBSTEPS] = 1;
    out[O_TRANSITIONS] = s->transitions[l];
    double floor = ENERGY_FLOOR_FRACTION * s->ps0[l] * s->depth[l];
    int pumped = s->excess[l] > ENERGY_SLACK * s->work_max[l] + floor || s->rest_rise[l] > floor;
    out[O_STATUS] = pumped ? 2 : 0;
    if (!(isfinite(s->y[l]) && isfinite(s->v[l]))) out[O_STATUS] = 3;
}

static inline void start_block(Block *s, int width, const double *params, const long *cases,
                               double grid_step) {
    memset(s, 0, sizeof(Block));
    for (int l = 0; l < width; l++) {
        const double *p = params + cases[l] * N_PARAMS;
        double inv_mass = 1.0 / p[P_MASS], damping = p[P_DRIVE_DAMPING] * inv_mass;
        double preload = p[P_PRELOAD] * inv_mass, tau = grid_step / p[P_SPEED];
        s->k[l] = p[P_DRIVE_STIFFNESS] * inv_mass;
        s->b[l] = damping;
        s->ks[l] = p[P_SPRING_RATE] * inv_mass;
        s->ps0[l] = preload;
        s->kz[l] = p[P_SEAT_STIFFNESS] * inv_mass;
        s->bz[l] = p[P_SEAT_DAMPING] * inv_mass;
        s->gamma[l] = p[P_EXTERNAL_DAMPING] * inv_mass;
        s->depth[l] = p[P_PRELOAD] / p[P_SEAT_STIFFNESS];
        s->speed[l] = p[P_SPEED];
        s->b_speed[l] = damping * p[P_SPEED];
        s->band[l] = TRANSITION_BAND * preload;
        s->mass[l] = p[P_MASS];
        s->tau[l] = tau;
        s->half_tau[l] = 0.5 * tau;
        s->sixth_tau[l] = tau / 6.0;
        s->time_step[l] = tau;
        s->y[l] = p[P_INITIAL_LIFT];
        s->v[l] = p[P_INITIAL_VELOCITY];
        s->inv_speed[l] = 1.0 / p[P_SPEED];
        s->max_lift[l] = s->max_v[l] = s->max_a[l] = s->excess[l] = s->rest_rise[l] = -INFINITY;
        s->min_v[l] = s->min_a[l] = s->jump_start[l] = INFINITY;
        s->energy0[l] = s->rest_energy[l] = NAN;
    }
}

/* One block of `width` lanes (a compile-time constant once inlined). */
static inline __attribute__((always_inline)) void run_block(
    const REAL *exc, long nodes, double table_step, double table_start, const double *params,
    const long *cases, int width, double *out) {
    Block s;
    long n_steps = (nodes - 1) / 2;
    double grid_step = 2.0 * table_step;
    start_block(&s, width, params, cases, grid_step);
    const REAL *lift_row = exc, *slope_row = exc + nodes, *curvature_row = exc + 2 * nodes;
    long nose = 0; /* first maximum of the theoretical lift */
    for (long i = 1; i < nodes; i++)
        if (lift_row[i] > lift_row[nose]) nose = i;
    for (long n = 0; n <= n_steps; n++) {
        REAL drive_lift = clip_lift(lift_row[2 * n]);
        REAL slope = clip_slope(lift_row[2 * n], slope_row[2 * n]);
        REAL angle = (REAL)(table_start + n * grid_step);
        int event = 0;
#pragma omp simd reduction(| : event)
        for (int l = 0; l < width; l++) {
            REAL drive, seat;
            REAL push = s.k[l] * drive_lift + s.b_speed[l] * slope;
            REAL a = acceleration(&s, l, s.y[l], s.v[l], push, &drive, &seat);
            s.acc[l] = a;
            event |= observe(&s, l, angle, s.y[l], s.v[l], a, drive_lift, s.speed[l] * slope,
                             drive, seat, n == 0, 2 * n >= nose);
        }
        if (event) {
            REAL y_prev = lift_row[2 * n - 2];
            for (int l = 0; l < width; l++)
                record_events(&s, l, clip_lift(y_prev), clip_slope(y_prev, slope_row[2 * n - 2]),
                              clip_slope(y_prev, curvature_row[2 * n - 2]));
        }
        if (n % ENERGY_INTERVAL == 0 || n == n_steps) {
#pragma omp simd
            for (int l = 0; l < width; l++) {
                REAL drive, seat;
                REAL push = s.k[l] * drive_lift + s.b_speed[l] * slope;
                acceleration(&s, l, s.y[l], s.v[l], push, &drive, &seat);
                observe_energy(&s, l, s.y[l], s.v[l], drive_lift, s.speed[l] * slope, drive);
            }
        }
        if (n == n_steps) break;
        REAL ym = clip_lift(lift_row[2 * n + 1]), sm = clip_slope(lift_row[2 * n + 1], slope_row[2 * n + 1]);
        REAL y1 = clip_lift(lift_row[2 * n + 2]), s1 = clip_slope(lift_row[2 * n + 2], slope_row[2 * n + 2]);
#pragma omp simd
        for (int l = 0; l < width; l++) {
            REAL y = s.y[l], v = s.v[l], a = s.acc[l], h = s.tau[l], hh = s.half_tau[l];
            REAL push_mid = s.k[l] * ym + s.b_speed[l] * sm;
            REAL push_end = s.k[l] * y1 + s.b_speed[l] * s1;
            REAL drive, seat;
            s.prev_y[l] = y;
            s.prev_v[l] = v;
            REAL p2 = y + hh * v, v2 = v + hh * a;
            REAL a2 = acceleration(&s, l, p2, v2, push_mid, &drive, &seat);
            REAL p3 = y + hh * v2, v3 = v + hh * a2;
            REAL a3 = acceleration(&s, l, p3, v3, push_mid, &drive, &seat);
            REAL p4 = y + h * v3, v4 = v + h * a3;
            REAL a4 = acceleration(&s, l, p4, v4, push_end, &drive, &seat);
            s.y[l] = y + s.sixth_tau[l] * (v + 2 * (v2 + v3) + v4);
            s.v[l] = v + s.sixth_tau[l] * (a + 2 * (a2 + a3) + a4);
        }
    }
    for (int l = 0; l < width; l++) finish(&s, l, grid_step, out + cases[l] * N_OUT);
}

/* exc: rows Y [m], Y' [m/rad], Y'' [m/rad^2] of `nodes` values at spacing table_step [rad] from table_start
 * [rad]; params: n_cases × N_PARAMS; out: n_cases × N_OUT (written). */
void valve_lanes(const REAL *exc, long nodes, double table_step, double table_start,
                 const double *params, long n_cases, double *out) {
    long n_blocks = (n_cases + LANES - 1) / LANES;
#pragma omp parallel for schedule(dynamic, 4)
    for (long b = 0; b < n_blocks; b++) {
        long cases[LANES];
        for (int l = 0; l < LANES; l++) {
            long i = b * LANES + l;
            cases[l] = i < n_cases ? i : b * LANES;
        }
        run_block(exc, nodes, table_step, table_start, params, cases, LANES, out);
    }
}

void valve_one_case(const REAL *exc, long nodes, double table_step, double table_start,
                    const double *params, long n_cases, double *out) {
#pragma omp parallel for schedule(dynamic, 64)
    for (long i = 0; i < n_cases; i++) {
        long cases[1] = {i};
        run_block(exc, nodes, table_step, table_start, params, cases, 1, out);
    }
}
