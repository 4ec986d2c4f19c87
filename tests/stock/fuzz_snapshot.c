/* fuzz_snapshot.c: libFuzzer target for the snapshot reader's metadata
 * (fm_stock_load_vdb in lib/stock/snapshot.c: parse_meta, the per-tool and
 * per-block tables, and fm_tool_marks_decode in tool_marks.c). A damaged
 * file is refused by its FNV-1a checksum, so fuzzing whole files would only
 * test the checksum: the input here is the metadata section alone, wrapped
 * into a valid file (header with the right lengths, the OpenVDB payload of a
 * real snapshot, the right checksum). LLVMFuzzerInitialize makes that
 * snapshot: a 12 mm box at 1 mm voxels cut by two tools, so that it has
 * tool marks of both record kinds. Any metadata must give either a stock
 * or an error, never a crash, a leak or an unbounded allocation.
 *
 * FUZZ_SNAPSHOT_SEED=<folder> writes the seed corpus into <folder> and
 * exits (how tests/stock/corpus_snapshot/ was made): the real snapshot's
 * metadata, the same as version 1 (no tool marks) and with no marks. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fuzz_input_file.h"

#include "fields.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define HEADER 32
#define BUDGET ((size_t)64 << 20)

static unsigned char header[HEADER]; /* the real snapshot's, lengths rewritten per input */
static unsigned char *vdb;           /* the real snapshot's OpenVDB bytes */
static size_t vdb_len;
static unsigned char *file;          /* the file being built */
static size_t file_cap;

static void put_le64(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++) p[i] = (unsigned char)(v >> (8 * i));
}

static uint64_t get_le64(const unsigned char *p)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--) v = (v << 8) | p[i];
    return v;
}

static void die(const char *what, const fm_error *err)
{
    fprintf(stderr, "fuzz_snapshot: %s%s%s\n", what, err ? ": " : "", err ? err->message : "");
    abort();
}

/* In $TMPDIR if set, else in /dev/shm (tmpfs), else in /tmp. */
static const char *scratch_dir(int i)
{
    const char *dir = getenv("TMPDIR");
    return i == 0 ? (dir && *dir ? dir : "/dev/shm") : "/tmp";
}

/* The real snapshot: saved by fm_stock_save into a fresh folder, read
 * back, split into header, metadata and OpenVDB bytes. */
static unsigned char *make_snapshot(size_t *meta_len)
{
    fm_error err;
    fm_stock_options opt;
    fm_stock_options_default(&opt);
    opt.voxel_mm = 1.0;
    opt.threads = 1;
    const double lo[3] = {0, 0, 0}, hi[3] = {12, 12, 12};
    fm_stock *s = fm_stock_new_box(lo, hi, &opt, &err);
    if (!s) die("box stock", &err);
    /* tool 7 takes a ball out of the top; tool 9 overlaps it, so some
     * leaves hold marks of both tools */
    const shape cuts[2] = {make_sphere(4, 6, 12, 4), make_sphere(8, 6, 12, 4)};
    const fm_stock_cut how[2] = {{7, 10, 0.0, 1.0}, {9, 11, 1.0, 2.5}};
    for (int i = 0; i < 2; i++) {
        fm_field f = shape_field(&cuts[i]);
        if (fm_stock_subtract(s, &f, &how[i], NULL, &err)) die("cut", &err);
    }
    char dir[1024] = "", path[1100];
    for (int i = 0; i < 2 && !dir[0]; i++) {
        snprintf(dir, sizeof dir, "%s/fuzz_snapshot_seed.XXXXXX", scratch_dir(i));
        if (!mkdtemp(dir)) dir[0] = '\0';
    }
    if (!dir[0]) die("cannot create a scratch folder", NULL);
    snprintf(path, sizeof path, "%s/seed.vdb", dir);
    if (fm_stock_save(s, path, "job 1 block 12", &err)) die("save", &err);
    fm_stock_free(s);

    char *text;
    size_t n;
    if (fm_file_read(path, "snapshot", (size_t)1 << 30, &text, &n, &err))
        die("cannot reopen the snapshot", &err);
    const unsigned char *p = (const unsigned char *)text;
    unlink(path);
    rmdir(dir);
    if (n < HEADER + 8) die("snapshot too short", NULL);
    const uint64_t mlen = get_le64(p + 16), vlen = get_le64(p + 24);
    if (HEADER + mlen + vlen + 8 != n) die("snapshot lengths do not add up", NULL);
    memcpy(header, p, HEADER);
    vdb_len = (size_t)vlen;
    vdb = malloc(vdb_len);
    if (!vdb) die("out of memory", NULL);
    memcpy(vdb, p + HEADER + mlen, vdb_len);
    unsigned char *meta = malloc((size_t)mlen);
    if (!meta) die("out of memory", NULL);
    memcpy(meta, p + HEADER, (size_t)mlen);
    free(text);
    *meta_len = (size_t)mlen;
    return meta;
}

static void write_seed(const char *dir, const char *name, const unsigned char *p, size_t n)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(p, 1, n, f) != n || fclose(f) != 0) die("cannot write a seed", NULL);
    printf("%s: %zu bytes\n", path, n);
}

/* The seeds: the real metadata; the same as version 1 (no tool marks
 * section); and with an empty tool marks section (no slots, no records). */
static void write_seeds(const char *dir, unsigned char *meta, size_t len)
{
    write_seed(dir, "real.meta", meta, len);
    size_t at = 4 + 8 + 4 + 8 + 8 + 8;
    at += 4 + 12 * (size_t)(meta[at] | meta[at + 1] << 8); /* tools (fewer than 65536) */
    at += 4 + 32 * (size_t)(meta[at] | meta[at + 1] << 8); /* blocks */
    at += 4 + (size_t)(meta[at] | meta[at + 1] << 8);      /* resume string */
    if (at + 8 > len) die("unexpected metadata layout", NULL);
    unsigned char *q = malloc(at + 8 + 12);
    if (!q) die("out of memory", NULL);
    memcpy(q, meta, at);
    q[0] = 1;
    write_seed(dir, "version1.meta", q, at);
    q[0] = meta[0];
    memset(q + at, 0, 20);
    q[at] = 12; /* u64 marks length 12: u32 0 slots, u64 0 records */
    write_seed(dir, "unmarked.meta", q, at + 20);
    free(q);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    size_t meta_len = 0;
    unsigned char *meta = make_snapshot(&meta_len);
    const char *seeds = getenv("FUZZ_SNAPSHOT_SEED");
    if (seeds && *seeds) {
        write_seeds(seeds, meta, meta_len);
        printf("(OpenVDB payload %zu bytes)\n", vdb_len);
        free(meta);
        free(vdb);
        exit(0);
    }
    free(meta);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const size_t n = HEADER + size + vdb_len + 8;
    if (n > file_cap) {
        free(file);
        file = malloc(n);
        if (!file) abort();
        file_cap = n;
    }
    memcpy(file, header, HEADER);
    put_le64(file + 16, size);
    put_le64(file + 24, vdb_len);
    if (size) memcpy(file + HEADER, data, size);
    memcpy(file + HEADER + size, vdb, vdb_len);
    uint64_t h = 0xcbf29ce484222325ULL; /* FNV-1a 64 */
    for (size_t i = 0; i < n - 8; i++) h = (h ^ file[i]) * 0x100000001b3ULL;
    put_le64(file + n - 8, h);
    const char *input_path = fuzz_input_file("fuzz_snapshot", file, n);

    fm_stock_options opt;
    fm_stock_options_default(&opt);
    opt.memory_budget = BUDGET;
    opt.threads = 1;
    fm_error err;
    fm_error_clear(&err);
    fm_stock *s = fm_stock_load_vdb(input_path, &opt, &err);
    if (s) {
        /* what a resumed job reads back */
        const char *resume = fm_stock_resume_string(s);
        if (!resume) abort();
        fm_stock_tool_volume tv[8];
        const size_t nt = fm_stock_tool_volumes(s, tv, 8);
        for (size_t i = 1; i < nt && i < 8; i++)
            if (tv[i - 1].tool >= tv[i].tool) abort();
        fm_stock_block b[8];
        fm_stock_blocks(s, b, 8);
        /* the marks answer for any voxel, in the grid or far outside */
        const int32_t probes[4][3] = {{0, 0, 0}, {6, 6, 11}, {-8, 1 << 30, 7},
                                      {INT32_MIN, INT32_MAX, -1}};
        for (int i = 0; i < 4; i++) {
            int tool = 0;
            fm_stock_voxel_tool(s, probes[i], &tool);
        }
        fm_stock_free(s);
    } else if (err.code == FM_OK || !err.message[0]) {
        abort();
    }
    return 0;
}
