/* test_comp_intersect.c: Fanuc's cutter compensation C engine
 * (toolpaths/gcode/machine/comp_intersect.c) on its own. Every expected
 * point is worked out by hand from the rules in Fanuc's manuals as that
 * file states them (the comments show the arithmetic): G41/G42 around a
 * boss (alpha 90 and 135: the intersection rule; alpha 60 and 0: the two
 * extra vectors), a D change, a pocket corner, arcs (convex, concave,
 * line-arc inner and outer, arc-line, an arc-arc cusp, a near-tangent
 * junction), start-up and cancel blocks, a Fusion-style lead-in/lead-out,
 * w-only moves and dwells in offset mode (and past the look-ahead), and
 * every refusal with its line. Offsets: left normal of a direction (tu, tv) is
 * (-tv, tu), right normal (tv, -tu). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "test.h"
#include "toolpaths/gcode/machine/comp_intersect.h"

#define TOL 1e-9
#define MAXOUT 64

/* What the caller hands through: the block number. */
typedef struct payload {
    int block;
} payload;

typedef struct out {
    gc_compc_elem e[MAXOUT];
    int block[MAXOUT];
    int n;
} out;

static fm_status collect(void *ctx, const gc_compc_elem *e, fm_error *err)
{
    out *o = ctx;
    if (o->n == MAXOUT) return fm_error_set(err, FM_ERR_LIMIT, "test: too many elements");
    o->e[o->n] = *e;
    o->block[o->n] = ((const payload *)e->payload)->block;
    o->e[o->n].payload = NULL; /* valid during the callback only */
    o->n++;
    return FM_OK;
}

typedef struct run {
    gc_compc c;
    out o;
    fm_error err;
    fm_status st; /* the first failure */
} run;

static void begin(run *r, double u, double v, double w)
{
    memset(r, 0, sizeof *r);
    double cur[3] = {u, v, w};
    r->st = gc_compc_init(&r->c, sizeof(payload), collect, &r->o, cur, &r->err);
}

static void add(run *r, gc_compc_kind kind, double u, double v, double w, double cu, double cv,
                int turn, int block)
{
    if (r->st) return;
    payload p = {block};
    gc_compc_elem e;
    memset(&e, 0, sizeof e);
    e.kind = kind;
    e.end[0] = u;
    e.end[1] = v;
    e.end[2] = w;
    e.center[0] = cu;
    e.center[1] = cv;
    e.turn = turn;
    e.file = "t.nc";
    e.line = block;
    e.column = 1;
    e.payload = &p;
    r->st = gc_compc_add(&r->c, &e, &r->err);
}

static void line(run *r, double u, double v, int block)
{
    add(r, GC_COMPC_LINE, u, v, 0, 0, 0, 0, block);
}

static void arc(run *r, double u, double v, double cu, double cv, int turn, int block)
{
    add(r, GC_COMPC_ARC, u, v, 0, cu, cv, turn, block);
}

static void start(run *r, gc_compc_side side, double radius, int block)
{
    if (!r->st) r->st = gc_compc_start(&r->c, side, radius, "t.nc", block, 1, &r->err);
}

static void cancel(run *r)
{
    if (!r->st) r->st = gc_compc_cancel(&r->c, &r->err);
}

static void finish(run *r)
{
    if (!r->st) r->st = gc_compc_finish(&r->c, &r->err);
    gc_compc_free(&r->c);
}

/* Output element i is a line (or corner move) from (su, sv) to (eu, ev)
 * belonging to block. */
#define CHECK_LINE(r, i, su, sv, eu, ev, blk, is_corner)                                    \
    do {                                                                                    \
        CHECK((r)->o.n > (i));                                                              \
        if ((r)->o.n <= (i)) break;                                                         \
        const gc_compc_elem *e_ = &(r)->o.e[i];                                             \
        CHECK(e_->kind == GC_COMPC_LINE);                                                   \
        CHECK_NEAR(e_->start[0], su, TOL);                                                  \
        CHECK_NEAR(e_->start[1], sv, TOL);                                                  \
        CHECK_NEAR(e_->end[0], eu, TOL);                                                    \
        CHECK_NEAR(e_->end[1], ev, TOL);                                                    \
        CHECK((r)->o.block[i] == (blk));                                                    \
        CHECK(e_->corner == (is_corner));                                                   \
    } while (0)

#define CHECK_ARC(r, i, su, sv, eu, ev, cu, cv, trn, blk)                                   \
    do {                                                                                    \
        CHECK((r)->o.n > (i));                                                              \
        if ((r)->o.n <= (i)) break;                                                         \
        const gc_compc_elem *e_ = &(r)->o.e[i];                                             \
        CHECK(e_->kind == GC_COMPC_ARC);                                                    \
        CHECK_NEAR(e_->start[0], su, TOL);                                                  \
        CHECK_NEAR(e_->start[1], sv, TOL);                                                  \
        CHECK_NEAR(e_->end[0], eu, TOL);                                                    \
        CHECK_NEAR(e_->end[1], ev, TOL);                                                    \
        CHECK_NEAR(e_->center[0], cu, TOL);                                                 \
        CHECK_NEAR(e_->center[1], cv, TOL);                                                 \
        CHECK(e_->turn == (trn));                                                           \
        CHECK((r)->o.block[i] == (blk));                                                    \
        CHECK(e_->corner == 0);                                                             \
    } while (0)

/* The boss 0..40 x 0..20, tool radius 5. Every corner has alpha = 90
 * degrees (the boss's square corner, on the workpiece side): Fanuc's
 * obtuse rule, the offset lines' intersection. */
static void test_boss_g41(void)
{
    run r;
    begin(&r, -10, -10, 0);
    start(&r, GC_COMPC_LEFT, 5, 1);
    line(&r, 0, 0, 1);   /* start-up */
    line(&r, 0, 20, 2);  /* up the left side (boss on the right: clockwise) */
    line(&r, 40, 20, 3);
    line(&r, 40, 0, 4);
    line(&r, 0, 0, 5);
    cancel(&r);
    line(&r, -10, -10, 6);
    finish(&r);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 6);
    /* start-up: to (0,0) + 5 * left normal of block 2's direction (0,1),
     * (-1,0): (-5, 0) */
    CHECK_LINE(&r, 0, -10, -10, -5, 0, 1, 0);
    /* block 2 offset x = -5; block 3 (direction (1,0), normal (0,1)) offset
     * y = 25: they meet at (-5, 25) */
    CHECK_LINE(&r, 1, -5, 0, -5, 25, 2, 0);
    /* block 4 (direction (0,-1), normal (1,0)) offset x = 45: (45, 25) */
    CHECK_LINE(&r, 2, -5, 25, 45, 25, 3, 0);
    /* block 5 (direction (-1,0), normal (0,-1)) offset y = -5: (45, -5) */
    CHECK_LINE(&r, 3, 45, 25, 45, -5, 4, 0);
    /* G40: block 5 ends at its end's perpendicular vector, (0,0) + 5 (0,-1) */
    CHECK_LINE(&r, 4, 45, -5, 0, -5, 5, 0);
    /* the cancel block: from there to its programmed end */
    CHECK_LINE(&r, 5, 0, -5, -10, -10, 6, 0);
}

static void test_boss_g42(void)
{
    run r;
    begin(&r, -10, -10, 0);
    start(&r, GC_COMPC_RIGHT, 5, 1);
    line(&r, 0, 0, 1);
    line(&r, 40, 0, 2); /* boss on the left: counter-clockwise */
    line(&r, 40, 20, 3);
    line(&r, 0, 20, 4);
    line(&r, 0, 0, 5);
    cancel(&r);
    line(&r, -10, -10, 6);
    finish(&r);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 6);
    /* start-up: (0,0) + 5 * right normal of (1,0), (0,-1): (0, -5) */
    CHECK_LINE(&r, 0, -10, -10, 0, -5, 1, 0);
    /* y = -5 meets block 3's x = 45 (right normal of (0,1) is (1,0)) */
    CHECK_LINE(&r, 1, 0, -5, 45, -5, 2, 0);
    /* block 4 (-1,0), right normal (0,1): y = 25 */
    CHECK_LINE(&r, 2, 45, -5, 45, 25, 3, 0);
    /* block 5 (0,-1), right normal (-1,0): x = -5 */
    CHECK_LINE(&r, 3, 45, 25, -5, 25, 4, 0);
    /* G40: (0,0) + 5 (-1,0) */
    CHECK_LINE(&r, 4, -5, 25, -5, 0, 5, 0);
    CHECK_LINE(&r, 5, -5, 0, -10, -10, 6, 0);
}

/* The G41 boss with D changed to radius 3 before block 3: block 3 and
 * after are offset by 3. The corner between blocks 2 and 3 meets block 2's
 * offset x = -5 and block 3's y = 20 + 3; the next one x = 40 + 3 and
 * y = 23. */
static void test_radius_change(void)
{
    run r;
    begin(&r, -10, -10, 0);
    start(&r, GC_COMPC_LEFT, 5, 1);
    line(&r, 0, 0, 1);
    line(&r, 0, 20, 2);
    if (!r.st) r.st = gc_compc_set_radius(&r.c, 3, "t.nc", 3, 1, &r.err);
    line(&r, 40, 20, 3);
    line(&r, 40, 0, 4);
    finish(&r);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 4);
    CHECK_LINE(&r, 1, -5, 0, -5, 23, 2, 0);
    CHECK_LINE(&r, 2, -5, 23, 43, 23, 3, 0);
    /* finish: (40,0) + 3 (1,0) */
    CHECK_LINE(&r, 3, 43, 23, 43, 0, 4, 0);
}

/* An equilateral triangle boss (0,0) (10,0) (5, 5 sqrt 3), counter-clockwise
 * with G42 (boss on the left), radius 1: the corner at (10,0) has alpha =
 * 60 degrees, Fanuc's acute rule with two extra vectors. */
static void test_boss_acute(void)
{
    double s3 = sqrt(3.0);
    run r;
    begin(&r, -5, -5, 0);
    start(&r, GC_COMPC_RIGHT, 1, 1);
    line(&r, 0, 0, 1);
    line(&r, 10, 0, 2);
    line(&r, 5, 5 * s3, 3);
    cancel(&r);
    line(&r, 5, 15, 4);
    finish(&r);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 5);
    /* start-up: (0,0) + right normal of (1,0) = (0,-1) */
    CHECK_LINE(&r, 0, -5, -5, 0, -1, 1, 0);
    /* t1 = (1,0), n1 = (0,-1); t2 = (-1/2, s3/2), n2 = (s3/2, 1/2).
     * a1 = (10,-1), extended by r along t1: (11, -1) */
    CHECK_LINE(&r, 1, 0, -1, 11, -1, 2, 0);
    /* a2 = (10 + s3/2, 1/2), backed up by r along t2:
     * (10 + s3/2 + 1/2, 1/2 - s3/2); the move between belongs to block 3 */
    CHECK_LINE(&r, 2, 11, -1, 10.5 + s3 / 2, 0.5 - s3 / 2, 3, 1);
    /* block 3 ends at (5, 5 s3) + n2 (G40 follows) */
    CHECK_LINE(&r, 3, 10.5 + s3 / 2, 0.5 - s3 / 2, 5 + s3 / 2, 5 * s3 + 0.5, 3, 0);
    CHECK_LINE(&r, 4, 5 + s3 / 2, 5 * s3 + 0.5, 5, 15, 4, 0);
}

/* A boss corner of alpha 135 degrees (G41, (1,0) then a right turn of 45
 * degrees to (1,-1)/sqrt 2 at (10,0)), radius 1: the offset lines y = 1
 * and the one through a2 = (10,0) + (1,1)/sqrt 2 meet at
 * (10 + tan 22.5 degrees, 1) = (9 + sqrt 2, 1), where the acute rule would
 * give (11,1) and (10, sqrt 2). (At alpha 90 the two rules agree.) */
static void test_boss_obtuse(void)
{
    double s2 = sqrt(2.0);
    run r;
    begin(&r, 0, 5, 0);
    start(&r, GC_COMPC_LEFT, 1, 1);
    line(&r, 0, 0, 1);
    line(&r, 10, 0, 2);
    line(&r, 20, -10, 3);
    finish(&r);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 3);
    CHECK_LINE(&r, 1, 0, 1, 9 + s2, 1, 2, 0);
    /* finish: (20,-10) + (1,1)/sqrt 2 */
    CHECK_LINE(&r, 2, 9 + s2, 1, 20 + 1 / s2, -10 + 1 / s2, 3, 0);
}

/* A line reversing on itself (alpha 0): the acute rule too. Radius 1, G41:
 * t1 = (1,0), n1 = (0,1), t2 = (-1,0), n2 = (0,-1) at (10,0):
 * (10,1) + (1,0) = (11,1); (10,-1) - (-1,0) = (11,-1). */
static void test_reversal(void)
{
    run r;
    begin(&r, 0, 5, 0);
    start(&r, GC_COMPC_LEFT, 1, 1);
    line(&r, 0, 0, 1);
    line(&r, 10, 0, 2);
    line(&r, 0, 0, 3);
    finish(&r);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 4);
    CHECK_LINE(&r, 0, 0, 5, 0, 1, 1, 0);
    CHECK_LINE(&r, 1, 0, 1, 11, 1, 2, 0);
    CHECK_LINE(&r, 2, 11, 1, 11, -1, 3, 1);
    /* finish: block 3 ends at (0,0) + n2 = (0,-1) */
    CHECK_LINE(&r, 3, 11, -1, 0, -1, 3, 0);
}

/* A pocket 0..40 x 0..30, G41 counter-clockwise inside (the tool on the
 * left, inside), radius 5: inner corners (alpha 270), intersections. */
static void test_pocket(void)
{
    run r;
    begin(&r, 20, 15, 0);
    start(&r, GC_COMPC_LEFT, 5, 1);
    line(&r, 20, 0, 1);
    line(&r, 40, 0, 2);
    line(&r, 40, 30, 3);
    line(&r, 20, 30, 4);
    cancel(&r);
    line(&r, 20, 15, 5);
    finish(&r);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 5);
    /* start-up: (20,0) + 5 (0,1) (block 2 runs (1,0)) */
    CHECK_LINE(&r, 0, 20, 15, 20, 5, 1, 0);
    /* y = 5 meets x = 35 (block 3 (0,1), left normal (-1,0)) */
    CHECK_LINE(&r, 1, 20, 5, 35, 5, 2, 0);
    /* x = 35 meets y = 25 (block 4 (-1,0), left normal (0,-1)) */
    CHECK_LINE(&r, 2, 35, 5, 35, 25, 3, 0);
    /* G40: (20,30) + 5 (0,-1) */
    CHECK_LINE(&r, 3, 35, 25, 20, 25, 4, 0);
    CHECK_LINE(&r, 4, 20, 25, 20, 15, 5, 0);
}

/* The same pocket 8 high with a tool of radius 5: block 3 (up x = 40)
 * would run from (35, 5) (y = 5 meets x = 35) to (35, 3) (x = 35 meets
 * y = 8 - 5): downward, against its direction. Refused at line 3. */
static void test_pocket_too_small(void)
{
    run r;
    begin(&r, 20, 4, 0);
    start(&r, GC_COMPC_LEFT, 5, 1);
    line(&r, 20, 0, 1);
    line(&r, 40, 0, 2);
    line(&r, 40, 8, 3);
    line(&r, 0, 8, 4);
    line(&r, 0, 0, 5);
    finish(&r);
    CHECK(r.st == FM_ERR_INPUT);
    CHECK(r.err.line == 3);
    CHECK_STR_CONTAINS(r.err.file, "t.nc");
    CHECK_STR_CONTAINS(r.err.message, "would reverse");
    CHECK_STR_CONTAINS(r.err.message, "smaller tool");
    /* what came before the refused block came out */
    CHECK(r.o.n == 2);
}

/* A notch 3 wide and 5 deep in a profile cut with G41 from left to right
 * (the tool above, the part below), radius 2 (diameter 4 > 3): the notch's
 * floor (10,-5) -> (13,-5) offsets to y = -3 and meets the walls' offsets
 * x = 12 (down x = 10: left normal (1,0)) and x = 11 (up x = 13: left
 * normal (-1,0)): from (12,-3) to (11,-3), reversed. Refused at line 4. */
static void test_gouge_step(void)
{
    run r;
    begin(&r, -5, 5, 0);
    start(&r, GC_COMPC_LEFT, 2, 1);
    line(&r, 0, 0, 1);
    line(&r, 10, 0, 2);
    line(&r, 10, -5, 3);
    line(&r, 13, -5, 4);
    line(&r, 13, 0, 5);
    line(&r, 20, 0, 6);
    finish(&r);
    CHECK(r.st == FM_ERR_INPUT);
    CHECK(r.err.line == 4);
    CHECK_STR_CONTAINS(r.err.message, "Fanuc alarm 041");
    /* start-up (0,2); block 2 to (12,2) (alpha 90: y = 2 meets x = 12);
     * block 3 from (12,2) to (12,-3) (inner: x = 12 meets y = -3) */
    CHECK(r.o.n == 3);
    CHECK_LINE(&r, 1, 0, 2, 12, 2, 2, 0);
    CHECK_LINE(&r, 2, 12, 2, 12, -3, 3, 0);
}

/* A concave fillet too short for the tool: G41 inside (counter-clockwise),
 * radius 2; the line (0,0) -> (10,0), a tangent fillet counter-clockwise
 * about (10,3), radius 3, from -90 to -60 degrees (to (11.5, 3 - 1.5 sqrt 3)),
 * then a line straight up (a 60-degree inner corner). The offset arc
 * (radius 1) starts at -90 degrees (tangent) and meets the second line's
 * offset x = 9.5 at -120 degrees ((9.5 - 10)^2 + (y - 3)^2 = 1): from -90
 * back to -120, a reversed sweep. Refused at the fillet's line. */
static void test_gouge_arc(void)
{
    run r;
    begin(&r, 0, 5, 0);
    start(&r, GC_COMPC_LEFT, 2, 1);
    line(&r, 0, 0, 1);
    line(&r, 10, 0, 2);
    arc(&r, 11.5, 3 - 1.5 * sqrt(3.0), 10, 3, 1, 3);
    line(&r, 11.5, 10, 4);
    finish(&r);
    CHECK(r.st == FM_ERR_INPUT);
    CHECK(r.err.line == 3);
    CHECK_STR_CONTAINS(r.err.message, "arc would run backwards");
}

/* A line, a tangent counter-clockwise quarter arc about (10,10) radius 10
 * from (10,0) to (20,10), a tangent line up x = 20; radius 2. */
static void tangent_profile(run *r, gc_compc_side side)
{
    begin(r, 0, -5, 0);
    start(r, side, 2, 1);
    line(r, 0, 0, 1);
    line(r, 10, 0, 2);
    arc(r, 20, 10, 10, 10, 1, 3);
    line(r, 20, 20, 4);
    finish(r);
}

static void test_arc_convex_concave(void)
{
    run r;
    /* G42: the tool right of a counter-clockwise arc, outside: radius
     * 10 + 2; the line y = -2 ends at (10,-2) on it (tangent: no extra
     * element), the arc ends at (22,10) where x = 22 starts */
    tangent_profile(&r, GC_COMPC_RIGHT);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 4);
    CHECK_LINE(&r, 0, 0, -5, 0, -2, 1, 0);
    CHECK_LINE(&r, 1, 0, -2, 10, -2, 2, 0);
    CHECK_ARC(&r, 2, 10, -2, 22, 10, 10, 10, 1, 3);
    CHECK_LINE(&r, 3, 22, 10, 22, 20, 4, 0);
    /* G41: inside, radius 10 - 2 */
    tangent_profile(&r, GC_COMPC_LEFT);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 4);
    CHECK_LINE(&r, 1, 0, 2, 10, 2, 2, 0);
    CHECK_ARC(&r, 2, 10, 2, 18, 10, 10, 10, 1, 3);
    CHECK_LINE(&r, 3, 18, 10, 18, 20, 4, 0);
}

/* A line (0,0) -> (10,0), then a half circle counter-clockwise about (20,0)
 * from (10,0) down through (20,-10) to (30,0): the arc starts going (0,-1),
 * a right turn of 90 degrees. Radius 2. */
static void line_arc_corner(run *r, gc_compc_side side)
{
    begin(r, -5, 0, 0);
    start(r, side, 2, 1);
    line(r, 0, 0, 1);
    line(r, 10, 0, 2);
    arc(r, 30, 0, 20, 0, 1, 3);
    cancel(r);
    line(r, 40, 10, 4);
    finish(r);
}

static void test_line_arc_corners(void)
{
    run r;
    /* G42: an inner corner. The line's offset y = -2 meets the offset
     * circle about (20,0) of radius 10 + 2 (the tool outside) at
     * (x-20)^2 + 4 = 144, x = 20 - sqrt(140) (the root by the corner). */
    line_arc_corner(&r, GC_COMPC_RIGHT);
    double x = 20 - sqrt(140.0);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 4);
    CHECK_LINE(&r, 0, -5, 0, 0, -2, 1, 0);
    CHECK_LINE(&r, 1, 0, -2, x, -2, 2, 0);
    /* the arc ends (G40) at (30,0) + 2 * right normal of (0,1) = (32,0) */
    CHECK_ARC(&r, 2, x, -2, 32, 0, 20, 0, 1, 3);
    CHECK_LINE(&r, 3, 32, 0, 40, 10, 4, 0);

    /* G41: an outer corner of alpha 90. The line's offset y = 2 and the
     * arc's tangent line at its offset start (10,0) + 2 (1,0) = (12,0),
     * x = 12, meet at (12,2): the line ends there, a corner move of block 3
     * goes down to (12,0), the arc (inside: radius 8) runs to its G40 end
     * (30,0) + 2 * left normal of (0,1) = (28,0). */
    line_arc_corner(&r, GC_COMPC_LEFT);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 5);
    CHECK_LINE(&r, 1, 0, 2, 12, 2, 2, 0);
    CHECK_LINE(&r, 2, 12, 2, 12, 0, 3, 1);
    CHECK_ARC(&r, 3, 12, 0, 28, 0, 20, 0, 1, 3);
    CHECK_LINE(&r, 4, 28, 0, 40, 10, 4, 0);
}

/* An arc then a line at an outer corner: the clockwise upper half circle
 * about (10,0), radius 10, from (0,0) to (20,0), then the line to (30,0),
 * G42 (the tool inside the arc: radius 8), radius 2. At (20,0) the arc runs
 * (0,-1) (right normal (-1,0): a1 = (18,0)), the line (1,0) (right normal
 * (0,-1): a2 = (20,-2)): a left turn with the tool on the right, alpha 90.
 * The arc's tangent line x = 18 meets y = -2 at (18,-2): the arc ends at
 * a1 and a corner move of the arc's block goes down to (18,-2), where the
 * line starts. */
static void test_arc_line_corner(void)
{
    run r;
    begin(&r, -5, -5, 0);
    start(&r, GC_COMPC_RIGHT, 2, 1);
    line(&r, 0, 0, 1);
    arc(&r, 20, 0, 10, 0, -1, 2);
    line(&r, 30, 0, 3);
    finish(&r);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 4);
    /* start-up: the arc starts at (0,0) going (0,1), right normal (1,0) */
    CHECK_LINE(&r, 0, -5, -5, 2, 0, 1, 0);
    CHECK_ARC(&r, 1, 2, 0, 18, 0, 10, 0, -1, 2);
    CHECK_LINE(&r, 2, 18, 0, 18, -2, 2, 1);
    /* finish: (30,0) + 2 (0,-1) */
    CHECK_LINE(&r, 3, 18, -2, 30, -2, 3, 0);
}

/* Two half circles (bumps) about (10,0) and (30,0), radius 10, meeting at
 * (20,0) in a cusp, the tool outside: an inner corner (the tangents are
 * opposite there; the bumps bend apart). Radius 2: the offset circles of
 * radius 12 meet at x = 20, y = +-sqrt(144 - 100) = +-sqrt(44), the one on
 * the tool's side (before the first arc's end). mirror = 1: the bumps
 * clockwise above the axis with G41; -1: counter-clockwise below it with
 * G42 (every v negated). */
static void test_arc_arc_cusp(int mirror)
{
    run r;
    double m = mirror;
    begin(&r, -5, -5 * m, 0);
    start(&r, mirror > 0 ? GC_COMPC_LEFT : GC_COMPC_RIGHT, 2, 1);
    line(&r, 0, 0, 1);
    arc(&r, 20, 0, 10, 0, -mirror, 2);
    arc(&r, 40, 0, 30, 0, -mirror, 3);
    cancel(&r);
    line(&r, 45, -5 * m, 4);
    finish(&r);
    double y = sqrt(44.0) * m;
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 4);
    /* start-up: the first arc starts at (0,0) going (0,m); the tool side
     * there is (-1,0) */
    CHECK_LINE(&r, 0, -5, -5 * m, -2, 0, 1, 0);
    CHECK_ARC(&r, 1, -2, 0, 20, y, 10, 0, -mirror, 2);
    /* G40: (40,0) going (0,-m), the tool side (1,0): (42,0) */
    CHECK_ARC(&r, 2, 20, y, 42, 0, 30, 0, -mirror, 3);
    CHECK_LINE(&r, 3, 42, 0, 45, -5 * m, 4, 0);
}

/* A near-tangent junction as rounded CAM output makes it: the line (0,0) ->
 * (10,0), then a counter-clockwise arc about (10.0005, 5) (its start
 * tangent is 1e-4 rad to the right of the line's), G41 radius 1. Within
 * the tangent tolerance: the line ends at its offset end (10,1) and one
 * straight move of the arc's block reaches the arc's offset start
 * (10,0) + (0.0005, 5) / R, R = sqrt(25 + 0.0005^2) (the left normal of
 * the tangent (5, -0.0005) / R), not the outer corner's intersection
 * (10.00005, 1) with two moves. */
static void test_near_tangent(void)
{
    double rr = sqrt(25 + 0.0005 * 0.0005);
    run r;
    begin(&r, 0, 5, 0);
    start(&r, GC_COMPC_LEFT, 1, 1);
    line(&r, 0, 0, 1);
    line(&r, 10, 0, 2);
    arc(&r, 15.0005, 5, 10.0005, 5, 1, 3);
    finish(&r);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 4);
    CHECK_LINE(&r, 1, 0, 1, 10, 1, 2, 0);
    CHECK_LINE(&r, 2, 10, 1, 10 + 0.0005 / rr, 5 / rr, 3, 1);
    /* finish: (15.0005, 5) + (-1, 0) */
    CHECK_ARC(&r, 3, 10 + 0.0005 / rr, 5 / rr, 14.0005, 5, 10.0005, 5, 1, 3);
}

/* Fusion 360 / Mastercam style: G41 D1 on a start-up line, a tangent
 * quarter arc lead-in onto the wall x = 0 (going up, boss on the right), the
 * wall, a tangent quarter arc lead-out, G40 G1 off the part. Radius 2. */
static void test_lead_in_out(void)
{
    run r;
    begin(&r, -15, -5, 0);
    start(&r, GC_COMPC_LEFT, 2, 1);
    line(&r, -5, -5, 1);             /* G41 D1 G1 X-5 Y-5 */
    arc(&r, 0, 0, -5, 0, 1, 2);      /* G3 X0 Y0 R5 (lead-in) */
    line(&r, 0, 20, 3);              /* the wall */
    arc(&r, -5, 25, -5, 20, 1, 4);   /* G3 X-5 Y25 R5 (lead-out) */
    cancel(&r);
    line(&r, -15, 25, 5);            /* G40 G1 X-15 */
    finish(&r);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 5); /* every junction tangent: no corner element */
    /* start-up: the lead-in starts at (-5,-5) going (1,0) (counter-clockwise
     * about (-5,0)); left normal (0,1): (-5,-3) */
    CHECK_LINE(&r, 0, -15, -5, -5, -3, 1, 0);
    /* the tool is inside the counter-clockwise lead-in: radius 5 - 2; it
     * ends at (0,0) + 2 (-1,0) = (-2,0), where the wall's offset x = -2
     * starts */
    CHECK_ARC(&r, 1, -5, -3, -2, 0, -5, 0, 1, 2);
    CHECK_LINE(&r, 2, -2, 0, -2, 20, 3, 0);
    /* lead-out about (-5,20), radius 3, ends (G40) at (-5,25) + 2 * left
     * normal of (-1,0) = (-5,23) */
    CHECK_ARC(&r, 3, -2, 20, -5, 23, -5, 20, 1, 4);
    CHECK_LINE(&r, 4, -5, 23, -15, 25, 5, 0);
}

/* The G41 boss of test_boss_g41 with a w-only move and a dwell between
 * blocks 2 and 3: the corner is the same (-5,25); they come out there, in
 * order, after block 2. */
static void test_non_plane_between(void)
{
    run r;
    begin(&r, -10, -10, 0);
    start(&r, GC_COMPC_LEFT, 5, 1);
    line(&r, 0, 0, 1);
    line(&r, 0, 20, 2);
    add(&r, GC_COMPC_LINE, 0, 20, -1, 0, 0, 0, 10); /* G1 Z-1 */
    add(&r, GC_COMPC_OTHER, 0, 0, 0, 0, 0, 0, 11);  /* G4 P1 */
    add(&r, GC_COMPC_LINE, 40, 20, -1, 0, 0, 0, 3); /* G1 X40 (Z stays -1) */
    finish(&r);
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == 5);
    CHECK_LINE(&r, 1, -5, 0, -5, 25, 2, 0);
    CHECK_LINE(&r, 2, -5, 25, -5, 25, 10, 0);
    CHECK_NEAR(r.o.e[2].start[2], 0, TOL);
    CHECK_NEAR(r.o.e[2].end[2], -1, TOL);
    CHECK(r.o.e[3].kind == GC_COMPC_OTHER && r.o.block[3] == 11);
    CHECK_NEAR(r.o.e[3].start[0], -5, TOL);
    CHECK_NEAR(r.o.e[3].start[1], 25, TOL);
    CHECK_NEAR(r.o.e[3].end[2], -1, TOL);
    /* block 3 at w = -1; finish ends it at (40,20) + 5 (0,1) */
    CHECK_LINE(&r, 4, -5, 25, 40, 25, 3, 0);
    CHECK_NEAR(r.o.e[4].start[2], -1, TOL);
    CHECK_NEAR(r.o.e[4].end[2], -1, TOL);
}

/* GC_COMPC_LOOKAHEAD + 1 dwells between blocks 2 and 3: the look-ahead
 * runs out at the last one, block 2 ends at its perpendicular vector
 * (0,20) + 5 (-1,0) = (-5,20), and block 3 starts with a corner move to its
 * own offset start (0,20) + 5 (0,1) = (0,25). */
static void test_lookahead_exhausted(void)
{
    run r;
    begin(&r, -10, -10, 0);
    start(&r, GC_COMPC_LEFT, 5, 1);
    line(&r, 0, 0, 1);
    line(&r, 0, 20, 2);
    for (int i = 0; i <= GC_COMPC_LOOKAHEAD; i++)
        add(&r, GC_COMPC_OTHER, 0, 0, 0, 0, 0, 0, 100 + i);
    line(&r, 40, 20, 3);
    finish(&r);
    int n = 2 + GC_COMPC_LOOKAHEAD + 1;
    CHECK(r.st == FM_OK);
    CHECK(r.o.n == n + 2);
    CHECK_LINE(&r, 1, -5, 0, -5, 20, 2, 0);
    for (int i = 0; i <= GC_COMPC_LOOKAHEAD; i++) CHECK(r.o.block[2 + i] == 100 + i);
    CHECK_LINE(&r, n, -5, 20, 0, 25, 3, 1);
    CHECK_LINE(&r, n + 1, 0, 25, 40, 25, 3, 0);
}

static void test_refusals(void)
{
    run r;
    /* an arc as the start-up block (Fanuc alarm 034) */
    begin(&r, 0, 0, 0);
    start(&r, GC_COMPC_LEFT, 1, 1);
    arc(&r, 10, 0, 5, 0, 1, 2);
    finish(&r);
    CHECK(r.st == FM_ERR_INPUT && r.err.line == 2);
    CHECK_STR_CONTAINS(r.err.message, "cannot start");
    CHECK_STR_CONTAINS(r.err.message, "034");
    /* an arc as the cancel block */
    begin(&r, 0, 0, 0);
    start(&r, GC_COMPC_LEFT, 1, 1);
    line(&r, 10, 0, 1);
    line(&r, 20, 0, 2);
    cancel(&r);
    arc(&r, 30, 0, 25, 0, 1, 3);
    finish(&r);
    CHECK(r.st == FM_ERR_INPUT && r.err.line == 3);
    CHECK_STR_CONTAINS(r.err.message, "cannot cancel");
    /* a counter-clockwise arc of radius 1 with G41 (the tool inside) and a
     * tool radius 2 */
    begin(&r, 0, -5, 0);
    start(&r, GC_COMPC_LEFT, 2, 1);
    line(&r, 0, 0, 1);
    line(&r, 10, 0, 2);
    arc(&r, 11, 1, 10, 1, 1, 3);
    finish(&r);
    CHECK(r.st == FM_ERR_INPUT && r.err.line == 3);
    CHECK_STR_CONTAINS(r.err.message, "inside an arc");
    /* a zero radius, and G41 twice */
    begin(&r, 0, 0, 0);
    start(&r, GC_COMPC_LEFT, 0, 1);
    CHECK(r.st == FM_ERR_INPUT && r.err.line == 1);
    gc_compc_free(&r.c);
    begin(&r, 0, 0, 0);
    start(&r, GC_COMPC_LEFT, 1, 1);
    start(&r, GC_COMPC_RIGHT, 1, 2);
    CHECK(r.st == FM_ERR_INPUT && r.err.line == 2);
    gc_compc_free(&r.c);
}

int main(void)
{
    test_boss_g41();
    test_boss_g42();
    test_boss_acute();
    test_radius_change();
    test_reversal();
    test_pocket();
    test_pocket_too_small();
    test_gouge_step();
    test_gouge_arc();
    test_arc_convex_concave();
    test_line_arc_corners();
    test_arc_line_corner();
    test_arc_arc_cusp(1);
    test_arc_arc_cusp(-1);
    test_boss_obtuse();
    test_lead_in_out();
    test_near_tangent();
    test_non_plane_between();
    test_lookahead_exhausted();
    test_refusals();
    return test_summary("comp_intersect");
}
