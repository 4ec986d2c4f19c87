/* alloc_fail.c: the replacement allocator of alloc_fail.h. It forwards to
 * glibc's own allocator (the __libc_* entry points glibc exports for this
 * purpose) and only counts and, when armed, fails. Counting is per thread
 * for the failure (so that a test's Nth allocation is its own, not a worker
 * thread's) and global for the live blocks.
 *
 * One kind of allocation is never failed: one made where C++ cannot throw.
 * Destructors (and shared_ptr's disposal, which runs them) are noexcept, so
 * there a failure can only call std::terminate; OpenVDB's Tree::clear, run
 * by ~Tree, allocates the list of leaves it frees, and no caller can do
 * anything about that. The armed allocation's call stack is read (glibc's
 * backtrace and dladdr: the test is linked with -rdynamic so that the
 * OpenVDB code instantiated in it has names) and when a frame is such a
 * function the failure moves to the next allocation.
 *
 * For the same reason one more kind is not failed: an allocation made by
 * OpenVDB 10's RootNode itself. Its members that add a child (addLeaf,
 * touchLeaf, setValue...) do `child = new ChildT(...); mTable[key] =
 * NodeStruct(*child);`, and when the std::map's node cannot be allocated
 * the child leaks inside OpenVDB, whatever the caller does. (The two
 * allocations cannot be told apart from the call stack: the map's code is
 * inlined.) Nor is one made in OpenVDB's meshToVolume while it expands the
 * narrow band (mesh_to_volume_internal::ExpandNarrowband keeps the leaves
 * it allocates in raw pointers, which leak when a later allocation
 * throws), nor one made while OpenVDB reads a grid (io::Archive::readGrid:
 * RootNode::readTopology files each child in its map after the child has
 * read its own topology, so a failure there, or in the map's node, leaks
 * the child and everything under it). */
#define _GNU_SOURCE
#include "alloc_fail.h"

#include <dlfcn.h>
#include <errno.h>
#include <execinfo.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern void *__libc_malloc(size_t size);
extern void *__libc_calloc(size_t n, size_t size);
extern void *__libc_realloc(void *p, size_t size);
extern void __libc_free(void *p);
extern void *__libc_memalign(size_t alignment, size_t size);

static atomic_long live_blocks;
static _Thread_local long armed_count, armed_fail_at, armed_failed_at;
static _Thread_local int armed, armed_hit, paused;

/* The armed thread's blocks, by address (open addressing), with where they
 * were allocated: what alloc_fail_report_leaks prints. */
#define TRACK_SLOTS 16384
#define TRACK_FRAMES 10
typedef struct tracked {
    void *p;
    long seq;
    size_t size;
    int nframes;
    void *frames[TRACK_FRAMES];
} tracked;
static tracked track[TRACK_SLOTS];
static atomic_flag track_lock = ATOMIC_FLAG_INIT;
static atomic_long tracked_count;
#define TOMBSTONE ((void *)1)

static size_t slot_of(const void *p)
{
    return (size_t)(((uintptr_t)p >> 4) * 0x9E3779B97F4A7C15ULL >> 50) % TRACK_SLOTS;
}

static void lock(void)
{
    while (atomic_flag_test_and_set_explicit(&track_lock, memory_order_acquire)) {
    }
}

static void unlock(void)
{
    atomic_flag_clear_explicit(&track_lock, memory_order_release);
}

/* Record a block of the armed thread (called unpaused, armed). */
static void track_add(void *p, size_t size)
{
    tracked t = {p, armed_count, size, 0, {0}};
    paused++; /* backtrace may allocate */
    t.nframes = backtrace(t.frames, TRACK_FRAMES);
    paused--;
    lock();
    size_t i = slot_of(p);
    for (size_t k = 0; k < TRACK_SLOTS; k++, i = (i + 1) % TRACK_SLOTS) {
        if (track[i].p == NULL || track[i].p == TOMBSTONE) {
            track[i] = t;
            atomic_fetch_add(&tracked_count, 1);
            break;
        }
    }
    unlock();
}

/* Forget a block (any thread). */
static void track_remove(void *p)
{
    if (atomic_load(&tracked_count) == 0) return;
    lock();
    size_t i = slot_of(p);
    for (size_t k = 0; k < TRACK_SLOTS && track[i].p; k++, i = (i + 1) % TRACK_SLOTS) {
        if (track[i].p == p) {
            track[i].p = TOMBSTONE;
            atomic_fetch_sub(&tracked_count, 1);
            break;
        }
    }
    unlock();
}

static void track_clear(void)
{
    lock();
    memset(track, 0, sizeof track);
    atomic_store(&tracked_count, 0);
    unlock();
}

/* backtrace loads libgcc_s at its first call, which allocates for good:
 * done here, before any test counts live blocks. */
__attribute__((constructor)) static void warm_up(void)
{
    void *frames[4];
    Dl_info info;
    if (backtrace(frames, 4) > 0) (void)dladdr(frames[0], &info);
}

void alloc_fail_arm(long fail_at)
{
    track_clear();
    armed_count = 0;
    armed_fail_at = fail_at;
    armed_hit = 0;
    armed = 1;
}

long alloc_fail_disarm(void)
{
    armed = 0;
    return armed_count;
}

int alloc_fail_hit(void)
{
    return armed_hit;
}

long alloc_fail_failed_at(void)
{
    return armed_hit ? armed_failed_at : 0;
}

long alloc_fail_live(void)
{
    return atomic_load(&live_blocks);
}

void alloc_fail_pause(void)
{
    paused++;
}

void alloc_fail_resume(void)
{
    paused--;
}

long alloc_fail_report_leaks(FILE *out)
{
    long n = 0;
    paused++;
    lock();
    for (size_t i = 0; i < TRACK_SLOTS; i++) {
        const tracked *t = &track[i];
        if (!t->p || t->p == TOMBSTONE) continue;
        n++;
        fprintf(out, "  block %ld of the run, %zu bytes, allocated in:", t->seq, t->size);
        for (int f = 2; f < t->nframes; f++) {
            Dl_info info;
            if (dladdr(t->frames[f], &info) && info.dli_sname)
                fprintf(out, " %s", info.dli_sname);
            else
                fprintf(out, " %p", t->frames[f]);
            fprintf(out, f + 1 < t->nframes ? " <-" : "\n");
        }
    }
    unlock();
    paused--;
    return n;
}

/* What a return address is, by the name of its function (dladdr, which
 * searches the symbol tables: cached by address). */
enum { FRAME_OTHER = 1, FRAME_ALLOCATOR, FRAME_NO_THROW, FRAME_ROOT_NODE, FRAME_UNNAMED };
#define FRAME_CACHE 8192
static struct {
    void *pc;
    int kind;
} frame_cache[FRAME_CACHE];

static int classify(const char *s)
{
    if (!s) return FRAME_UNNAMED; /* a local function: GCC's clones, static helpers */
    size_t len = strlen(s);
    const char *end = s + (len >= 4 ? len - 4 : 0);
    if (!strncmp(s, "_Zn", 3) || !strcmp(s, "malloc") || !strcmp(s, "calloc") || !strcmp(s, "realloc") ||
        strstr(s, "memalign") || !strcmp(s, "aligned_alloc"))
        return FRAME_ALLOCATOR;
    if (!strcmp(end, "D0Ev") || !strcmp(end, "D1Ev") || !strcmp(end, "D2Ev") || strstr(s, "_M_dispose") ||
        strstr(s, "_M_release") || strstr(s, "_M_destroy") ||
        (strstr(s, "openvdb") && strstr(s, "4Tree") && strstr(s, "5clearEv")) ||
        strstr(s, "mesh_to_volume_internal16ExpandNarrowband") ||
        (strstr(s, "openvdb") && strstr(s, "7Archive8readGrid")))
        return FRAME_NO_THROW;
    if (strstr(s, "openvdb") && strstr(s, "8RootNode")) return FRAME_ROOT_NODE;
    return FRAME_OTHER;
}

static int frame_kind(void *pc)
{
    size_t i = (size_t)(((uintptr_t)pc * 0x9E3779B97F4A7C15ULL) >> 51) % FRAME_CACHE;
    if (frame_cache[i].pc == pc) return frame_cache[i].kind;
    Dl_info info;
    int kind = classify(dladdr(pc, &info) ? info.dli_sname : NULL);
    frame_cache[i].pc = pc;
    frame_cache[i].kind = kind;
    return kind;
}

/* Can a failure here only end in std::terminate or a leak inside a
 * library (see the top of this file)? */
static int cannot_throw_here(void)
{
    void *frames[64];
    paused++; /* backtrace and dladdr may allocate */
    int n = backtrace(frames, 64);
    int found = 0, first_caller = 1;
    for (int i = 1; i < n && !found; i++) {
        int kind = frame_kind(frames[i]);
        found = kind == FRAME_NO_THROW || (first_caller && kind == FRAME_ROOT_NODE);
        if (kind != FRAME_ALLOCATOR && kind != FRAME_UNNAMED && i > 1) first_caller = 0;
    }
    if (getenv("ALLOC_FAIL_DEBUG")) {
        for (int i = 0; i < n && i < 8; i++) {
            Dl_info info;
            fprintf(stderr, "   %d kind %d %.120s\n", i, frame_kind(frames[i]),
                    dladdr(frames[i], &info) && info.dli_sname ? info.dli_sname : "?");
        }
        fprintf(stderr, "   -> %s\n", found ? "not failed" : "failed");
    }
    paused--;
    return found;
}

/* Is this allocation the one to fail? */
static int fail_now(void)
{
    if (!armed || paused) return 0;
    if (++armed_count != armed_fail_at) return 0;
    if (cannot_throw_here()) {
        armed_fail_at++;
        return 0;
    }
    armed_hit = 1;
    armed_failed_at = armed_count;
    errno = ENOMEM;
    return 1;
}

static void *counted(void *p, size_t size)
{
    if (p) {
        atomic_fetch_add(&live_blocks, 1);
        if (armed && !paused) track_add(p, size);
    }
    return p;
}

void *malloc(size_t size)
{
    return fail_now() ? NULL : counted(__libc_malloc(size), size);
}

void *calloc(size_t n, size_t size)
{
    return fail_now() ? NULL : counted(__libc_calloc(n, size), n * size);
}

void free(void *p)
{
    if (!p) return;
    atomic_fetch_sub(&live_blocks, 1);
    track_remove(p);
    __libc_free(p);
}

void *realloc(void *p, size_t size)
{
    if (!p) return malloc(size);
    if (size == 0) {
        /* glibc frees the block and returns NULL. */
        free(p);
        return NULL;
    }
    /* A failed realloc leaves the block as it was. */
    if (fail_now()) return NULL;
    void *q = __libc_realloc(p, size);
    if (q) {
        track_remove(p);
        if (armed && !paused) track_add(q, size);
    }
    return q;
}

static void *aligned(size_t alignment, size_t size)
{
    return fail_now() ? NULL : counted(__libc_memalign(alignment, size), size);
}

void *memalign(size_t alignment, size_t size)
{
    return aligned(alignment, size);
}

void *aligned_alloc(size_t alignment, size_t size)
{
    return aligned(alignment, size);
}

int posix_memalign(void **out, size_t alignment, size_t size)
{
    if (alignment < sizeof(void *) || (alignment & (alignment - 1)) != 0) return EINVAL;
    void *p = aligned(alignment, size);
    if (!p) return ENOMEM;
    *out = p;
    return 0;
}

void *valloc(size_t size)
{
    return aligned(4096, size);
}

void *pvalloc(size_t size)
{
    return aligned(4096, (size + 4095) & ~(size_t)4095);
}
