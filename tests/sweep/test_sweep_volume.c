/* test_sweep_volume.c: volumes of swept solids, integrated over an
 * adaptive grid, against closed forms: a slot, a ring, a ball along a
 * helix (tube formula), a flat end mill along a helix in a bore (a 1D
 * integral of the z-extent, derived in docs/sweep.md), a drill plunge.
 *
 * Two bounds on the grid's error, both asserted:
 * - rigorous: cells whose interval says inside or outside are exact; each
 *   finest cell left (N of them, side s) counts by the sign of S at one
 *   point of it, and its whole volume goes into the bound, so
 *   |V_grid - V| <= N s^3 (2-11% of V here: it cannot see a sweep 1% off);
 * - Hoeffding: that point is drawn uniformly in its cell (fixed seed), so
 *   each cell's count is an independent variable in [0, s^3] whose mean is
 *   the cell's inside volume: V_grid is unbiased and
 *   P(|V_grid - V| >= t) <= 2 exp(-2 t^2 / (N s^6)). With t =
 *   sqrt(N s^6 ln(2 / 1e-9) / 2) the grid is within t of V but for odds
 *   of 1e-9, whatever the surface's shape: 0.004-0.06% of V here, so a
 *   sweep whose volume is 1% off fails (docs/sweep.md). */
#include "test.h"
#include "sweep/sweep_cases.h"

typedef struct vol_acc {
    double vol, err;
    size_t cells, uncertain;
} vol_acc;

/* ln(2 / 1e-9): the Hoeffding bound's odds of failing. */
static const double hoeffding_log = 21.416413017506358;

static void integrate(const fm_sweep *s, fm_sweep_worker *w, const double c[3], double h, int depth, vol_acc *a)
{
    fm_interval box[3];
    for (int i = 0; i < 3; i++) {
        box[i].lo = c[i] - h;
        box[i].hi = c[i] + h;
    }
    double cell = 8 * h * h * h;
    a->cells++;
    fm_interval iv = fm_sweep_interval(s, w, box);
    if (iv.lo >= 0) {
        a->vol += cell;
        return;
    }
    if (iv.hi < 0) return;
    if (depth == 0) {
        /* one draw per statement: an initializer list's order is unspecified */
        double q[3];
        for (int i = 0; i < 3; i++) q[i] = test_uniform(box[i].lo, box[i].hi);
        if (fm_sweep_eval(s, w, q) >= 0) a->vol += cell;
        a->err += cell;
        a->uncertain++;
        return;
    }
    for (int k = 0; k < 8; k++) {
        double cc[3] = {c[0] + (k & 1 ? 0.5 : -0.5) * h, c[1] + (k & 2 ? 0.5 : -0.5) * h,
                        c[2] + (k & 4 ? 0.5 : -0.5) * h};
        integrate(s, w, cc, 0.5 * h, depth - 1, a);
    }
}

/* Volume of S over its bounding box: root cubes of size `root`, refined
 * `levels` times. */
static vol_acc sweep_volume(const fm_motion *m, const fm_tool_part *part, double root, int levels)
{
    vol_acc a = {0, 0, 0, 0};
    fm_sweep *s;
    fm_error err;
    if (fm_sweep_new(m, part, NULL, &s, &err) != FM_OK) {
        fprintf(stderr, "%s\n", err.message);
        a.err = 1e300;
        return a;
    }
    fm_sweep_worker *w = fm_sweep_worker_new(s);
    double lo[3], hi[3];
    fm_sweep_bounds(s, lo, hi);
    int n[3];
    for (int i = 0; i < 3; i++) n[i] = (int)ceil((hi[i] - lo[i]) / root);
    for (int i = 0; i < n[0]; i++)
        for (int j = 0; j < n[1]; j++)
            for (int k = 0; k < n[2]; k++) {
                double c[3] = {lo[0] + (i + 0.5) * root, lo[1] + (j + 0.5) * root, lo[2] + (k + 0.5) * root};
                integrate(s, w, c, 0.5 * root, levels, &a);
            }
    fm_sweep_worker_free(w);
    fm_sweep_free(s);
    return a;
}

static void report(const char *name, vol_acc a, double exact)
{
    /* every uncertain cell is a finest one: the same size */
    double cell = a.uncertain ? a.err / (double)a.uncertain : 0;
    double t = sqrt((double)a.uncertain * cell * cell * hoeffding_log / 2);
    printf("%-18s exact %9.4f  grid %9.4f (%+.4f%%)  rigorous bound %.4f (%.2f%%)  Hoeffding bound %.4f "
           "(%.4f%%)  cells %zu, %zu uncertain\n",
           name, exact, a.vol, 100 * (a.vol - exact) / exact, a.err, 100 * a.err / exact, t, 100 * t / exact,
           a.cells, a.uncertain);
    CHECK(fabs(a.vol - exact) <= a.err);
    CHECK(fabs(a.vol - exact) <= t);
}

static fm_tool_part flat_part(double diameter, double flute)
{
    fm_tool_spec s = sc_spec(FM_TOOL_FLAT);
    s.diameter = diameter;
    s.flute_length = flute;
    fm_tool t;
    fm_error err;
    if (fm_tool_build(&s, &t, &err) != FM_OK) fprintf(stderr, "%s\n", err.message);
    return t.flutes;
}

/* Flat end mill (radius R, height H) whose tip runs one full turn of a
 * helix of radius Ra < R and pitch p <= H. Over a point at distance rho
 * from the helix axis the tool is present for the angles within alpha(rho)
 * of the point's own angle; averaging the covered z-extent over that angle
 * (docs/sweep.md) gives H + p/(2 pi) ((2 pi - 2 alpha) alpha / pi + 2 alpha). */
static double bore_volume(double R, double H, double Ra, double p)
{
    int n = 2000000;
    double b = R + Ra, h = b / n, sum = 0;
    for (int i = 0; i < n; i++) {
        double rho = (i + 0.5) * h, alpha;
        if (rho <= R - Ra) {
            alpha = FM_PI;
        } else {
            double c = (rho * rho + Ra * Ra - R * R) / (2 * rho * Ra);
            alpha = acos(c > 1 ? 1 : c < -1 ? -1 : c);
        }
        double ext = H + p / (2 * FM_PI) * ((2 * FM_PI - 2 * alpha) * alpha / FM_PI + 2 * alpha);
        sum += 2 * FM_PI * rho * ext;
    }
    return sum * h;
}

int main(void)
{
    const int L = 6;     /* 1 mm roots refined 6 times: finest cells 1/64 mm */
    /* Slot: flat d = 6, flute 3, 10 mm along X: L d depth + the two end caps. */
    fm_tool_part flat = flat_part(6, 3);
    fm_motion m = sc_line(0, 0, 0, 10, 0, 0);
    report("slot", sweep_volume(&m, &flat, 1, L), (10 * 6 + FM_PI * 9) * 3);
    /* Ring: full circle of radius 5: annulus pi ((5 + 3)^2 - (5 - 3)^2) times 3. */
    double c0[3] = {0, 0, 0};
    m = sc_arc(2, c0, 5, 0, 0, 1, 0);
    report("ring", sweep_volume(&m, &flat, 1, L), FM_PI * (64 - 4) * 3);
    /* Ball of radius 1 along one turn of a helix (radius 5, pitch 4): a tube,
     * pi r^2 length + the two half-ball caps (Weyl's tube formula; the
     * curvature radius 5.08 exceeds r and turns are 4 > 2r apart). */
    fm_profile_elem sph[2] = {{FM_PROFILE_ARC, {0, 0}, {1, 1}, {0, 1}, 1, 0},
                              {FM_PROFILE_ARC, {1, 1}, {0, 2}, {0, 1}, 1, 0}};
    fm_tool_part ball;
    fm_error err;
    CHECK(fm_tool_part_from_profile(sph, 2, &ball, &err) == FM_OK);
    m = sc_arc(2, c0, 5, 0, 0, 1, 4);
    double len = sqrt(pow(2 * FM_PI * 5, 2) + 16);
    report("ball helix", sweep_volume(&m, &ball, 1, 5), FM_PI * len + 4.0 / 3 * FM_PI);
    /* Flat d = 6, height 3, helix radius 1, pitch 2 down one turn (a bore). */
    m = sc_arc(2, c0, 1, 0, 0, 1, -2);
    report("flat helix (bore)", sweep_volume(&m, &flat, 1, 5), bore_volume(3, 3, 1, 2));
    /* Drill d = 6, 118 degrees, flute 10, plunged 5 mm: cylinder + point cone. */
    fm_tool_spec ds = sc_spec(FM_TOOL_DRILL);
    fm_tool drill;
    CHECK(fm_tool_build(&ds, &drill, &err) == FM_OK);
    m = sc_line(0, 0, 0, 0, 0, -5);
    double hc = 3 / tan(59 * FM_PI / 180);
    report("drill plunge", sweep_volume(&m, &drill.flutes, 1, L), FM_PI * 9 * (10 + 5 - hc) + FM_PI * 9 * hc / 3);
    return test_summary("sweep_volume");
}
