/* test_stock_marks.c: lib/stock's tool-mark table (tool_marks.c), against
 * a plain reference: a dense array of per-voxel tool numbers over a small
 * region. Random cuts set random voxel sets with random tools (uniform
 * leaves turning mixed), random boxes are cleared (both ways of clearing:
 * by leaf positions and by scanning the records), and after every step
 * every voxel of the region answers as the reference does; the snapshot
 * encoding round-trips, and damaged encodings are refused. An internal
 * test: it includes lib/stock's private record header. */
#include "stock/stock_impl.h"
#include "test.h"

#include <stdlib.h>

/* region: leaves -3..4 on each axis (64^3 voxels from -24 to 39) */
#define LO (-24)
#define N 64

static int ref[N][N][N]; /* tool number, or -1: never set */

static int marks_agree(const fm_tool_marks *m, const char *when)
{
    int bad = 0;
    for (int x = 0; x < N; x++)
        for (int y = 0; y < N; y++)
            for (int z = 0; z < N; z++) {
                const int32_t ijk[3] = {LO + x, LO + y, LO + z};
                int tool = -12345;
                const int got = fm_tool_marks_get(m, ijk, &tool);
                const int want = ref[x][y][z];
                if ((want < 0 && got) || (want >= 0 && (!got || tool != want))) {
                    if (bad < 3)
                        fprintf(stderr, "%s: voxel %d %d %d: got %d (tool %d), want %d\n", when,
                                ijk[0], ijk[1], ijk[2], got, tool, want);
                    bad++;
                }
            }
    return bad == 0;
}

static void random_cut(fm_tool_marks *m, int tool)
{
    const int slot = fm_tool_marks_slot(m, tool);
    CHECK(slot >= 0);
    const int leaves = 1 + (int)(test_rand01() * 12);
    for (int l = 0; l < leaves; l++) {
        int32_t o[3];
        for (int k = 0; k < 3; k++) o[k] = LO + 8 * (int)(test_rand01() * (N / 8));
        uint64_t set[8] = {0};
        const double density = test_rand01();
        for (int i = 0; i < 512; i++)
            if (test_rand01() < density) set[i >> 6] |= (uint64_t)1 << (i & 63);
        CHECK(fm_tool_marks_set(m, o, set, slot) == FM_OK);
        for (int i = 0; i < 512; i++)
            if ((set[i >> 6] >> (i & 63)) & 1)
                ref[o[0] - LO + (i >> 6)][o[1] - LO + ((i >> 3) & 7)][o[2] - LO + (i & 7)] = tool;
    }
}

static void random_clear(fm_tool_marks *m)
{
    int32_t lo[3], hi[3];
    const int big = test_rand01() < 0.3; /* larger than the table: the scan path */
    for (int k = 0; k < 3; k++) {
        const int a = LO + 8 * (int)(test_rand01() * (N / 8));
        const int len = big ? 8 * (3 + (int)(test_rand01() * 6)) : 8 * (1 + (int)(test_rand01() * 2));
        lo[k] = a;
        hi[k] = a + len - 1;
    }
    fm_tool_marks_clear(m, lo, hi);
    for (int x = lo[0]; x <= hi[0]; x++)
        for (int y = lo[1]; y <= hi[1]; y++)
            for (int z = lo[2]; z <= hi[2]; z++)
                if (x >= LO && x < LO + N && y >= LO && y < LO + N && z >= LO && z < LO + N)
                    ref[x - LO][y - LO][z - LO] = -1;
}

static void test_random_against_reference(void)
{
    for (int x = 0; x < N; x++)
        for (int y = 0; y < N; y++)
            for (int z = 0; z < N; z++) ref[x][y][z] = -1;
    fm_tool_marks m;
    memset(&m, 0, sizeof m);
    const int tools[5] = {0, 1, 7, 12, 40000};
    int ok = 1;
    for (int step = 0; step < 300 && ok; step++) {
        if (test_rand01() < 0.7)
            random_cut(&m, tools[(int)(test_rand01() * 5)]);
        else
            random_clear(&m);
        if (step % 10 == 9) {
            char when[32];
            snprintf(when, sizeof when, "step %d", step);
            ok = marks_agree(&m, when);
            CHECK(ok);
        }
    }
    printf("random marks: %zu leaves, %zu mixed, %zu slots after 300 steps\n", m.nleaves, m.mixed,
           m.nslots);
    CHECK(m.nleaves > 20 && m.mixed > 5);

    /* the encoding round-trips */
    size_t len = 0;
    unsigned char *bytes = fm_tool_marks_encode(&m, &len);
    CHECK(bytes != NULL);
    fm_tool_marks back;
    memset(&back, 0, sizeof back);
    fm_error err;
    CHECK(fm_tool_marks_decode(&back, bytes, len, "test", &err) == FM_OK);
    CHECK(back.nleaves == m.nleaves);
    CHECK(marks_agree(&back, "decoded"));
    fm_tool_marks_free(&back);

    /* damaged: every truncation, and a few changed bytes, are refused or
     * (where the change keeps it valid) decoded without harm */
    for (size_t cut = 0; cut < len; cut += 1 + cut / 8) {
        memset(&back, 0, sizeof back);
        CHECK(fm_tool_marks_decode(&back, bytes, cut, "test", &err) == FM_ERR_INPUT);
        CHECK(back.nleaves == 0 && back.index == NULL);
    }
    for (int i = 0; i < 200; i++) {
        const size_t at = (size_t)(test_rand01() * (double)len);
        const unsigned char old = bytes[at];
        bytes[at] ^= (unsigned char)(1 + (int)(test_rand01() * 255));
        memset(&back, 0, sizeof back);
        fm_status st = fm_tool_marks_decode(&back, bytes, len, "test", &err);
        CHECK(st == FM_OK || st == FM_ERR_INPUT);
        if (st != FM_OK) CHECK_STR_CONTAINS(err.message, "tool marks are malformed");
        fm_tool_marks_free(&back);
        bytes[at] = old;
    }
    free(bytes);
    fm_tool_marks_free(&m);
}

/* More tools than the slot table holds are refused, not lost silently. */
static void test_slot_limit(void)
{
    fm_tool_marks m;
    memset(&m, 0, sizeof m);
    for (int t = 0; t < FM_STOCK_MAX_TOOLS; t++) CHECK(fm_tool_marks_slot(&m, t * 3) == t);
    CHECK(fm_tool_marks_slot(&m, 3 * 17) == 17);
    CHECK(fm_tool_marks_slot(&m, -5) == -1);
    fm_tool_marks_free(&m);
}

int main(void)
{
    test_random_against_reference();
    test_slot_limit();
    return test_summary("stock_marks");
}
