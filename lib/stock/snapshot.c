/* snapshot.c: crash-safe stock snapshots. OpenVDB 10.0 has no checksum and
 * can corrupt its heap on a damaged file, so each .vdb payload is wrapped:
 *
 *   0   8  magic "FMSTOCK\n"
 *   8   4  format version (1), little-endian
 *   12  4  flags (0)
 *   16  8  metadata length M
 *   24  8  VDB length N
 *   32  M  metadata (what a resumed job needs; see put_meta)
 *   ..  N  OpenVDB stream bytes (Blosc-compressed)
 *   end 8  FNV-1a 64 of every byte before it
 *
 * and the whole file is read into memory (within the budget) and verified
 * before OpenVDB sees a byte. Writing goes to a temporary file in the same
 * folder, fsync, the old file becomes "<path>.prev", rename, fsync of the
 * folder. */
#include "stock/stock_impl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SNAP_MAGIC "FMSTOCK\n"
#define SNAP_VERSION 1u
#define SNAP_HEADER 32u
#define SNAP_TRAILER 8u
#define META_VERSION 2u /* 2 added the tool marks; 1 is still read */

/* ------------------------------------------------------------ hashing -- */

#define FNV_OFFSET 0xcbf29ce484222325ULL
#define FNV_PRIME 0x100000001b3ULL

static uint64_t fnv1a(uint64_t h, const unsigned char *p, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= FNV_PRIME;
    }
    return h;
}

/* ------------------------------------------------- little-endian bytes -- */

typedef struct wbuf {
    unsigned char *p;
    size_t len, cap;
    int failed;
} wbuf;

static void put_bytes(wbuf *b, const void *src, size_t n)
{
    if (b->failed) return;
    if (b->len + n > b->cap) {
        size_t cap = b->cap ? b->cap : 256;
        while (cap < b->len + n) cap *= 2;
        unsigned char *p = realloc(b->p, cap);
        if (!p) {
            b->failed = 1;
            return;
        }
        b->p = p;
        b->cap = cap;
    }
    memcpy(b->p + b->len, src, n);
    b->len += n;
}

static void put_u64(wbuf *b, uint64_t v)
{
    unsigned char x[8];
    for (int i = 0; i < 8; i++) x[i] = (unsigned char)(v >> (8 * i));
    put_bytes(b, x, 8);
}

static void put_u32(wbuf *b, uint32_t v)
{
    unsigned char x[4];
    for (int i = 0; i < 4; i++) x[i] = (unsigned char)(v >> (8 * i));
    put_bytes(b, x, 4);
}

static void put_f64(wbuf *b, double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    put_u64(b, u);
}

static uint64_t get_u64(const unsigned char *p)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--) v = (v << 8) | p[i];
    return v;
}

static uint32_t get_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

typedef struct rbuf {
    const unsigned char *p;
    size_t len, pos;
    int failed;
} rbuf;

static const unsigned char *take(rbuf *r, size_t n)
{
    if (r->failed || n > r->len - r->pos) {
        r->failed = 1;
        return NULL;
    }
    const unsigned char *p = r->p + r->pos;
    r->pos += n;
    return p;
}

static uint64_t take_u64(rbuf *r)
{
    const unsigned char *p = take(r, 8);
    return p ? get_u64(p) : 0;
}

static uint32_t take_u32(rbuf *r)
{
    const unsigned char *p = take(r, 4);
    return p ? get_u32(p) : 0;
}

static double take_f64(rbuf *r)
{
    uint64_t u = take_u64(r);
    double v;
    memcpy(&v, &u, 8);
    return v;
}

/* ---------------------------------------------------------- metadata -- */

/* voxel, band, version, initial and removed volume, the per-tool and
 * per-block tables, the caller's resume string, and (version 2) the tool
 * marks as u64 length + tool_marks.c's bytes. */
static void put_meta(wbuf *b, const fm_stock *s, const char *resume, const unsigned char *marks,
                     size_t marks_len)
{
    put_u32(b, META_VERSION);
    put_f64(b, fm_vdb_voxel(s->vdb));
    put_u32(b, (uint32_t)fm_vdb_band(s->vdb));
    put_u64(b, s->version);
    put_f64(b, s->initial_volume);
    put_f64(b, s->removed_total);
    put_u32(b, (uint32_t)s->ntools);
    for (size_t i = 0; i < s->ntools; i++) {
        put_u32(b, (uint32_t)s->tools[i].tool);
        put_f64(b, s->tools[i].removed_mm3);
    }
    put_u32(b, (uint32_t)s->nblocks);
    for (size_t i = 0; i < s->nblocks; i++) {
        put_u64(b, (uint64_t)s->blocks[i].block);
        put_f64(b, s->blocks[i].removed_mm3);
        put_f64(b, s->blocks[i].t0);
        put_f64(b, s->blocks[i].t1);
    }
    const size_t n = resume ? strlen(resume) : 0;
    put_u32(b, (uint32_t)n);
    put_bytes(b, resume ? resume : "", n);
    put_u64(b, marks_len);
    put_bytes(b, marks, marks_len);
}

typedef struct meta {
    double voxel;
    uint32_t band;
    uint64_t version;
    double initial, removed;
    uint32_t ntools;
    const unsigned char *tools; /* 12 bytes each */
    uint32_t nblocks;
    const unsigned char *blocks; /* 32 bytes each */
    uint32_t resume_len;
    const unsigned char *resume;
    uint64_t marks_len;
    const unsigned char *marks;
} meta;

static fm_status parse_meta(const unsigned char *p, size_t len, meta *m, const char *path,
                            fm_error *err)
{
    rbuf r = {p, len, 0, 0};
    const uint32_t v = take_u32(&r);
    if (!r.failed && v != META_VERSION && v != 1)
        return fm_error_set(err, FM_ERR_INPUT,
                            "%s: snapshot metadata version %u is not 1 or %u", path, v,
                            META_VERSION);
    m->voxel = take_f64(&r);
    m->band = take_u32(&r);
    m->version = take_u64(&r);
    m->initial = take_f64(&r);
    m->removed = take_f64(&r);
    m->ntools = take_u32(&r);
    m->tools = take(&r, (size_t)m->ntools * 12);
    m->nblocks = take_u32(&r);
    m->blocks = take(&r, (size_t)m->nblocks * 32);
    m->resume_len = take_u32(&r);
    m->resume = take(&r, m->resume_len);
    if (v >= 2) {
        m->marks_len = take_u64(&r);
        m->marks = m->marks_len <= len ? take(&r, (size_t)m->marks_len) : NULL;
        if (!m->marks) r.failed = 1;
    }
    if (r.failed || r.pos != len)
        return fm_error_set(err, FM_ERR_INPUT, "%s: snapshot metadata is malformed", path);
    if (!(m->voxel > 0) || m->band < 2 || m->band > 32 || m->ntools > FM_STOCK_MAX_TOOLS)
        return fm_error_set(err, FM_ERR_INPUT,
                            "%s: snapshot metadata out of range (voxel %g, band %u, %u tools)",
                            path, m->voxel, m->band, m->ntools);
    return FM_OK;
}

/* ------------------------------------------------------------- writing -- */

/* The file's parts in order, then the FNV-1a of all of them. */
typedef struct snapshot_parts {
    const unsigned char *p[3];
    size_t n[3];
} snapshot_parts;

static int write_parts(int fd, void *ctx)
{
    const snapshot_parts *parts = ctx;
    uint64_t hash = FNV_OFFSET;
    for (int i = 0; i < 3; i++) {
        hash = fnv1a(hash, parts->p[i], parts->n[i]);
        int e = fm_file_write_all(fd, parts->p[i], parts->n[i]);
        if (e) return e;
    }
    unsigned char trailer[8];
    for (int i = 0; i < 8; i++) trailer[i] = (unsigned char)(hash >> (8 * i));
    return fm_file_write_all(fd, trailer, 8);
}

fm_status fm_stock_save(const fm_stock *s, const char *path, const char *resume, fm_error *err)
{
    char prev[4096 + 16];
    if (!s || !path || !*path || snprintf(prev, sizeof prev, "%s.prev", path) >= (int)sizeof prev)
        return fm_error_set(err, FM_ERR_INPUT, "snapshot path \"%s\" is not a file path",
                            path ? path : "");

    size_t marks_len = 0;
    unsigned char *marks = fm_tool_marks_encode(&s->marks, &marks_len);
    if (!marks) return fm_error_set(err, FM_ERR_LIMIT, "snapshot not saved: out of memory");
    wbuf m = {0};
    put_meta(&m, s, resume, marks, marks_len);
    free(marks);
    unsigned char *vdb = NULL;
    size_t vdb_len = 0;
    if (m.failed) {
        free(m.p);
        return fm_error_set(err, FM_ERR_LIMIT, "snapshot not saved: out of memory");
    }
    fm_status rc = fm_vdb_write(s->vdb, &vdb, &vdb_len, err);
    if (rc) {
        free(m.p);
        return rc;
    }

    wbuf h = {0};
    put_bytes(&h, SNAP_MAGIC, 8);
    put_u32(&h, SNAP_VERSION);
    put_u32(&h, 0);
    put_u64(&h, m.len);
    put_u64(&h, vdb_len);

    if (h.failed) {
        rc = fm_error_set(err, FM_ERR_LIMIT, "snapshot not saved: out of memory");
        goto done;
    }
    snapshot_parts parts = {{h.p, m.p, vdb}, {h.len, m.len, vdb_len}};
    rc = fm_file_write_durable_with(path, "snapshot", write_parts, &parts, prev, err);
done:
    free(h.p);
    free(m.p);
    free(vdb);
    return rc;
}

/* ------------------------------------------------------------- loading -- */

fm_stock *fm_stock_load_vdb(const char *path, const fm_stock_options *opt_in, fm_error *err)
{
    fm_stock_options opt;
    if (fm_stock_options_resolve(opt_in, &opt, err)) return NULL;
    if (!path) {
        fm_error_set(err, FM_ERR_INPUT, "no snapshot path");
        return NULL;
    }
    char *data;
    size_t size;
    if (fm_file_read(path, "snapshot", opt.memory_budget, &data, &size, err)) return NULL;
    unsigned char *buf = (unsigned char *)data;
    fm_stock *s = NULL;
    if (size < SNAP_HEADER + SNAP_TRAILER) {
        fm_error_set(err, FM_ERR_INPUT, "%s: truncated snapshot (%llu bytes)", path,
                     (unsigned long long)size);
        goto out;
    }
    if (memcmp(buf, SNAP_MAGIC, 8) != 0) {
        fm_error_set(err, FM_ERR_INPUT, "%s: not a frepmill snapshot (bad magic number)", path);
        goto out;
    }
    const uint32_t version = get_u32(buf + 8);
    if (version != SNAP_VERSION) {
        fm_error_set(err, FM_ERR_INPUT, "%s: snapshot format version %u, this build reads %u",
                     path, version, SNAP_VERSION);
        goto out;
    }
    const uint64_t mlen = get_u64(buf + 16), vlen = get_u64(buf + 24);
    const uint64_t body = size - SNAP_HEADER - SNAP_TRAILER;
    if (mlen > body || vlen > body - mlen || mlen + vlen != body) {
        fm_error_set(err, FM_ERR_INPUT,
                     "%s: damaged snapshot: lengths %llu + %llu do not match the %llu bytes "
                     "present",
                     path, (unsigned long long)mlen, (unsigned long long)vlen,
                     (unsigned long long)body);
        goto out;
    }
    const uint64_t want = get_u64(buf + size - SNAP_TRAILER);
    const uint64_t have = fnv1a(FNV_OFFSET, buf, (size_t)(size - SNAP_TRAILER));
    if (want != have) {
        fm_error_set(err, FM_ERR_INPUT, "%s: damaged snapshot: checksum mismatch", path);
        goto out;
    }
    meta m;
    memset(&m, 0, sizeof m);
    if (parse_meta(buf + SNAP_HEADER, (size_t)mlen, &m, path, err)) goto out;

    /* verified: only now does OpenVDB see the bytes */
    fm_vdb *v = fm_vdb_read(buf + SNAP_HEADER + mlen, (size_t)vlen, opt.threads, err);
    if (!v) goto out;
    if (fabs(fm_vdb_voxel(v) - m.voxel) > 1e-9 * m.voxel || (uint32_t)fm_vdb_band(v) != m.band) {
        fm_error_set(err, FM_ERR_INPUT,
                     "%s: snapshot metadata (voxel %g, band %u) disagrees with its grid "
                     "(voxel %g, band %d)",
                     path, m.voxel, m.band, fm_vdb_voxel(v), fm_vdb_band(v));
        fm_vdb_free(v);
        goto out;
    }
    s = fm_stock_wrap(v, &opt, err);
    if (!s) goto out;
    /* every chunk counts as changed in the restored version: readers that
     * come back after a restart fetch everything once */
    s->version = m.version ? m.version : 1;
    for (size_t i = 0; i < s->cap_chunks; i++)
        if (s->chunks[i].used) s->chunks[i].version = s->version;
    s->initial_volume = m.initial;
    s->removed_total = m.removed;
    for (uint32_t i = 0; i < m.ntools; i++) {
        const unsigned char *t = m.tools + 12 * (size_t)i;
        double removed;
        uint64_t u = get_u64(t + 4);
        memcpy(&removed, &u, 8);
        fm_stock_add_tool(s, (int)get_u32(t), removed);
    }
    for (uint32_t i = 0; i < m.nblocks; i++) {
        const unsigned char *b = m.blocks + 32 * (size_t)i;
        double d[3];
        for (int k = 0; k < 3; k++) {
            uint64_t u = get_u64(b + 8 + 8 * k);
            memcpy(&d[k], &u, 8);
        }
        fm_stock_add_block(s, (int64_t)get_u64(b), d[0], d[1], d[2]);
    }
    if (m.marks && fm_tool_marks_decode(&s->marks, m.marks, (size_t)m.marks_len, path, err)) {
        fm_stock_free(s);
        s = NULL;
        goto out;
    }
    char *resume = malloc((size_t)m.resume_len + 1);
    if (!resume) {
        fm_error_set(err, FM_ERR_LIMIT, "%s: out of memory", path);
        fm_stock_free(s);
        s = NULL;
        goto out;
    }
    memcpy(resume, m.resume, m.resume_len);
    resume[m.resume_len] = '\0';
    free(s->resume);
    s->resume = resume;
out:
    free(buf);
    return s;
}

fm_stock *fm_stock_load_latest(const char *path, const fm_stock_options *opt, int *used_prev,
                               fm_error *err)
{
    if (used_prev) *used_prev = 0;
    fm_error first;
    fm_error_clear(&first);
    fm_stock *s = fm_stock_load_vdb(path, opt, &first);
    if (s || first.code == FM_ERR_LIMIT) {
        if (!s && err) *err = first;
        return s;
    }
    char prev[4096 + 16];
    if (snprintf(prev, sizeof prev, "%s.prev", path) >= (int)sizeof prev) {
        if (err) *err = first;
        return NULL;
    }
    fm_error second;
    fm_error_clear(&second);
    s = fm_stock_load_vdb(prev, opt, &second);
    if (s) {
        if (used_prev) *used_prev = 1;
        return s;
    }
    fm_error_set(err, first.code, "%.240s; and the previous generation: %.240s", first.message,
                 second.message);
    return NULL;
}

/* ------------------------------------------------------------ cleanup -- */

fm_status fm_stock_snapshot_cleanup(const char *dir, size_t *removed, fm_error *err)
{
    return fm_file_remove_stale_temporaries(dir, removed, err);
}
