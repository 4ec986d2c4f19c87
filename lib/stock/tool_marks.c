/* tool_marks.c: which tool last cut each voxel of the stock, for colouring
 * meshes by tool. The grid bridge reports, per cut, the leaves that keep a
 * surface and the voxels whose value the cut set; this file keeps one
 * record per such leaf: the set voxels as a 512-bit mask and, while one
 * tool did all of them, that tool alone (most leaves: 88 bytes beside the
 * grid's 2 KB leaf); per-voxel ids only where two tools share a leaf.
 * Tools are stored as slots (uint16) of a small slot -> tool number table.
 * The records travel in snapshots (encode / decode below). */
#include "stock/stock_impl.h"

#include <stdlib.h>
#include <string.h>

#define LEAF_VOXELS 512

static size_t leaf_slot_of(const fm_tool_marks *m, const int32_t origin[3])
{
    const int32_t k[3] = {origin[0] >> 3, origin[1] >> 3, origin[2] >> 3};
    return (size_t)fm_stock_hash3(k) & (m->index_size - 1);
}

static int same_origin(const int32_t a[3], const int32_t b[3])
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/* Index slot holding the record of origin, or the empty slot where it
 * would go. */
static size_t find_slot(const fm_tool_marks *m, const int32_t origin[3])
{
    size_t j = leaf_slot_of(m, origin);
    while (m->index[j] && !same_origin(m->leaves[m->index[j] - 1].origin, origin))
        j = (j + 1) & (m->index_size - 1);
    return j;
}

static fm_status grow_index(fm_tool_marks *m)
{
    size_t size = m->index_size ? m->index_size * 2 : 1024;
    uint32_t *idx = calloc(size, sizeof *idx);
    if (!idx) return FM_ERR_LIMIT;
    free(m->index);
    m->index = idx;
    m->index_size = size;
    for (size_t i = 0; i < m->nleaves; i++) m->index[find_slot(m, m->leaves[i].origin)] =
        (uint32_t)(i + 1);
    return FM_OK;
}

static fm_tool_leaf *leaf_get_or_add(fm_tool_marks *m, const int32_t origin[3])
{
    if (m->index_size) {
        size_t j = find_slot(m, origin);
        if (m->index[j]) return &m->leaves[m->index[j] - 1];
    }
    if (m->nleaves >= UINT32_MAX - 1) return NULL;
    if ((m->nleaves + 1) * 2 > m->index_size && grow_index(m)) return NULL;
    if (m->nleaves == m->cap_leaves) {
        size_t cap = m->cap_leaves ? m->cap_leaves * 2 : 256;
        fm_tool_leaf *t = realloc(m->leaves, cap * sizeof *t);
        if (!t) return NULL;
        m->leaves = t;
        m->cap_leaves = cap;
    }
    fm_tool_leaf *l = &m->leaves[m->nleaves];
    memset(l, 0, sizeof *l);
    memcpy(l->origin, origin, sizeof l->origin);
    m->index[find_slot(m, origin)] = (uint32_t)(++m->nleaves);
    return l;
}

/* Remove the record at index slot j: backward-shift deletion keeps the
 * linear probe chains whole; the last record moves into the hole. */
static void leaf_remove_at(fm_tool_marks *m, size_t j)
{
    const size_t e = m->index[j] - 1;
    const size_t mask = m->index_size - 1;
    if (m->leaves[e].ids) m->mixed--;
    free(m->leaves[e].ids);
    m->index[j] = 0;
    for (size_t k = (j + 1) & mask; m->index[k]; k = (k + 1) & mask) {
        const size_t home = leaf_slot_of(m, m->leaves[m->index[k] - 1].origin);
        /* the entry at k may fill the hole at j unless its home lies in (j, k] */
        const int stays = j <= k ? (home > j && home <= k) : (home > j || home <= k);
        if (stays) continue;
        m->index[j] = m->index[k];
        m->index[k] = 0;
        j = k;
    }
    const size_t last = m->nleaves - 1;
    if (e != last) {
        m->index[find_slot(m, m->leaves[last].origin)] = (uint32_t)(e + 1);
        m->leaves[e] = m->leaves[last];
    }
    m->nleaves--;
}

void fm_tool_marks_free(fm_tool_marks *m)
{
    for (size_t i = 0; i < m->nleaves; i++) free(m->leaves[i].ids);
    free(m->leaves);
    free(m->index);
    free(m->slot_tool);
    memset(m, 0, sizeof *m);
}

int fm_tool_marks_slot(fm_tool_marks *m, int tool)
{
    for (size_t i = 0; i < m->nslots; i++)
        if (m->slot_tool[i] == tool) return (int)i;
    if (m->nslots >= FM_STOCK_MAX_TOOLS) return -1;
    int *t = realloc(m->slot_tool, (m->nslots + 1) * sizeof *t);
    if (!t) return -1;
    m->slot_tool = t;
    m->slot_tool[m->nslots] = tool;
    return (int)m->nslots++;
}

fm_status fm_tool_marks_set(fm_tool_marks *m, const int32_t origin[3], const uint64_t set[8],
                            int slot)
{
    int any = 0;
    for (int w = 0; w < 8; w++) any |= set[w] != 0;
    if (!any) return FM_OK;
    fm_tool_leaf *l = leaf_get_or_add(m, origin);
    if (!l) return FM_ERR_LIMIT;
    const uint16_t id = (uint16_t)(slot + 1);
    int had = 0;
    for (int w = 0; w < 8; w++) had |= l->set[w] != 0;
    if (!l->ids && (!had || l->uniform == id)) {
        l->uniform = id;
        for (int w = 0; w < 8; w++) l->set[w] |= set[w];
        return FM_OK;
    }
    if (!l->ids) {
        l->ids = malloc(LEAF_VOXELS * sizeof *l->ids);
        if (!l->ids) return FM_ERR_LIMIT;
        for (int i = 0; i < LEAF_VOXELS; i++)
            l->ids[i] = (l->set[i >> 6] >> (i & 63)) & 1 ? l->uniform : 0;
        m->mixed++;
    }
    for (int i = 0; i < LEAF_VOXELS; i++)
        if ((set[i >> 6] >> (i & 63)) & 1) l->ids[i] = id;
    for (int w = 0; w < 8; w++) l->set[w] |= set[w];
    return FM_OK;
}

void fm_tool_marks_clear(fm_tool_marks *m, const int32_t lo[3], const int32_t hi[3])
{
    if (!m->nleaves) return;
    int32_t a[3], b[3];
    double positions = 1;
    for (int k = 0; k < 3; k++) {
        a[k] = lo[k] & ~7;
        b[k] = hi[k] & ~7;
        positions *= (double)(((int64_t)b[k] - a[k]) / 8 + 1);
    }
    if (positions <= (double)m->nleaves) {
        int32_t o[3];
        for (o[0] = a[0]; o[0] <= b[0]; o[0] += 8)
            for (o[1] = a[1]; o[1] <= b[1]; o[1] += 8)
                for (o[2] = a[2]; o[2] <= b[2]; o[2] += 8) {
                    size_t j = find_slot(m, o);
                    if (m->index[j]) leaf_remove_at(m, j);
                }
        return;
    }
    for (size_t i = m->nleaves; i-- > 0;) {
        const int32_t *o = m->leaves[i].origin;
        if (o[0] < a[0] || o[0] > b[0] || o[1] < a[1] || o[1] > b[1] || o[2] < a[2] ||
            o[2] > b[2])
            continue;
        /* removal moves the last record to i; going down, it was seen */
        leaf_remove_at(m, find_slot(m, o));
    }
}

int fm_tool_marks_get(const fm_tool_marks *m, const int32_t ijk[3], int *tool)
{
    if (!m->nleaves) return 0;
    const int32_t origin[3] = {ijk[0] & ~7, ijk[1] & ~7, ijk[2] & ~7};
    size_t j = find_slot(m, origin);
    if (!m->index[j]) return 0;
    const fm_tool_leaf *l = &m->leaves[m->index[j] - 1];
    const int i = ((ijk[0] & 7) << 6) | ((ijk[1] & 7) << 3) | (ijk[2] & 7);
    const uint16_t id = l->ids ? l->ids[i] : (((l->set[i >> 6] >> (i & 63)) & 1) ? l->uniform : 0);
    if (!id || id > m->nslots) return 0;
    if (tool) *tool = m->slot_tool[id - 1];
    return 1;
}

size_t fm_tool_marks_bytes(const fm_tool_marks *m)
{
    return m->cap_leaves * sizeof *m->leaves + m->index_size * sizeof *m->index +
           m->mixed * LEAF_VOXELS * sizeof(uint16_t) + m->nslots * sizeof *m->slot_tool;
}

size_t fm_tool_marks_used_bytes(const fm_tool_marks *m)
{
    return m->nleaves * sizeof *m->leaves + m->index_size * sizeof *m->index +
           m->mixed * LEAF_VOXELS * sizeof(uint16_t) + m->nslots * sizeof *m->slot_tool;
}

/* ------------------------------------------------------ serializing -- */
/* Little-endian: u32 slots, slots x i32 tool; u64 leaves; per leaf i32
 * x, y, z (multiples of 8), u8 kind; kind 0: u16 slot + 1, 8 x u64 set
 * mask; kind 1: 512 x u16 (slot + 1, 0 = never set). */

static unsigned char *put_le(unsigned char *p, uint64_t v, int bytes)
{
    for (int i = 0; i < bytes; i++) p[i] = (unsigned char)(v >> (8 * i));
    return p + bytes;
}

static uint64_t get_le(const unsigned char *p, int bytes)
{
    uint64_t v = 0;
    for (int i = 0; i < bytes; i++) v |= (uint64_t)p[i] << (8 * i);
    return v;
}

#define UNIFORM_RECORD (12 + 1 + 2 + 64)
#define MIXED_RECORD (12 + 1 + 2 * LEAF_VOXELS)

unsigned char *fm_tool_marks_encode(const fm_tool_marks *m, size_t *len)
{
    size_t n = 4 + 4 * m->nslots + 8;
    for (size_t i = 0; i < m->nleaves; i++)
        n += m->leaves[i].ids ? MIXED_RECORD : UNIFORM_RECORD;
    unsigned char *buf = malloc(n), *p = buf;
    if (!buf) return NULL;
    p = put_le(p, m->nslots, 4);
    for (size_t i = 0; i < m->nslots; i++) p = put_le(p, (uint32_t)m->slot_tool[i], 4);
    p = put_le(p, m->nleaves, 8);
    for (size_t i = 0; i < m->nleaves; i++) {
        const fm_tool_leaf *l = &m->leaves[i];
        for (int k = 0; k < 3; k++) p = put_le(p, (uint32_t)l->origin[k], 4);
        *p++ = l->ids ? 1 : 0;
        if (l->ids) {
            for (int v = 0; v < LEAF_VOXELS; v++) p = put_le(p, l->ids[v], 2);
        } else {
            p = put_le(p, l->uniform, 2);
            for (int w = 0; w < 8; w++) p = put_le(p, l->set[w], 8);
        }
    }
    *len = n;
    return buf;
}

fm_status fm_tool_marks_decode(fm_tool_marks *m, const unsigned char *p, size_t len,
                               const char *path, fm_error *err)
{
    const unsigned char *end = p + len;
    if (len < 12) goto malformed;
    const uint64_t nslots = get_le(p, 4);
    p += 4;
    if (nslots > FM_STOCK_MAX_TOOLS || (size_t)(end - p) < 4 * nslots + 8) goto malformed;
    for (uint64_t i = 0; i < nslots; i++, p += 4)
        if (fm_tool_marks_slot(m, (int)(int32_t)get_le(p, 4)) != (int)i) goto malformed;
    const uint64_t nleaves = get_le(p, 8);
    p += 8;
    /* every record takes at least UNIFORM_RECORD bytes: checked before a
     * byte of the table is allocated */
    if (nleaves > (uint64_t)(end - p) / UNIFORM_RECORD) goto malformed;
    for (uint64_t i = 0; i < nleaves; i++) {
        if ((size_t)(end - p) < UNIFORM_RECORD) goto malformed;
        int32_t o[3];
        for (int k = 0; k < 3; k++, p += 4) {
            o[k] = (int32_t)(uint32_t)get_le(p, 4);
            if (o[k] & 7) goto malformed;
        }
        const int kind = *p++;
        uint64_t set[8] = {0};
        if (kind == 0) {
            const uint64_t id = get_le(p, 2);
            p += 2;
            for (int w = 0; w < 8; w++, p += 8) set[w] = get_le(p, 8);
            if (id == 0 || id > nslots) goto malformed;
            if (fm_tool_marks_set(m, o, set, (int)id - 1)) goto oom;
        } else if (kind == 1) {
            if ((size_t)(end - p) < 2 * LEAF_VOXELS) goto malformed;
            /* one tool at a time, in the order met: a leaf whose voxels
             * all name one tool comes back as a uniform record */
            uint16_t ids[LEAF_VOXELS];
            for (int v = 0; v < LEAF_VOXELS; v++) {
                const uint64_t id = get_le(p + 2 * v, 2);
                if (id > nslots) goto malformed;
                ids[v] = (uint16_t)id;
            }
            for (int first = 0; first < LEAF_VOXELS; first++) {
                const uint16_t id = ids[first];
                if (!id) continue;
                memset(set, 0, sizeof set);
                for (int v = first; v < LEAF_VOXELS; v++)
                    if (ids[v] == id) {
                        set[v >> 6] |= (uint64_t)1 << (v & 63);
                        if (v > first) ids[v] = 0;
                    }
                if (fm_tool_marks_set(m, o, set, (int)id - 1)) goto oom;
            }
            p += 2 * LEAF_VOXELS;
        } else {
            goto malformed;
        }
    }
    if (p != end) goto malformed;
    return FM_OK;
malformed:
    fm_tool_marks_free(m);
    return fm_error_set(err, FM_ERR_INPUT, "%s: the snapshot's tool marks are malformed", path);
oom:
    fm_tool_marks_free(m);
    return fm_error_set(err, FM_ERR_LIMIT, "%s: out of memory restoring the tool marks", path);
}
