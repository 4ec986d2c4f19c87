/* alloc_fail.h: allocation-failure injection for tests, in the manner of
 * SQLite's malloc tests. alloc_fail.c replaces malloc, calloc, realloc, free
 * and the aligned allocators (glibc documents this replacement: every
 * allocation in the process, including C++ operator new in the OpenVDB
 * bridges, jansson and the C library itself, comes through it), counts the
 * allocations made on the armed thread and makes the Nth fail, and counts
 * the blocks alive in the whole process so that a test can prove that a
 * failed call freed everything it had allocated. Link it only into a test
 * executable, never with a sanitizer (which has its own allocator):
 * fm_test(... NO_SANITIZE). tests/README.md says how to use it. */
#ifndef FM_TESTS_ALLOC_FAIL_H
#define FM_TESTS_ALLOC_FAIL_H

#include <stdio.h>

/* Arm: the fail_at-th allocation (1-based; malloc, calloc, a realloc that
 * must allocate, aligned allocations) made from now on by this thread
 * returns NULL with errno ENOMEM; the others succeed. fail_at 0 counts
 * without failing. */
void alloc_fail_arm(long fail_at);

/* Disarm; returns how many allocations this thread made while armed. */
long alloc_fail_disarm(void);

/* Did the armed failure happen? (An input may need fewer allocations.) */
int alloc_fail_hit(void);

/* Which allocation failed: fail_at, or a later one when those from fail_at
 * on were not to be failed (alloc_fail.c says which are not). */
long alloc_fail_failed_at(void);

/* Blocks allocated and not yet freed, by every thread. */
long alloc_fail_live(void);

/* While paused (calls nest), this thread's allocations are neither counted
 * nor failed. alloc_fail_libs.c pauses over jansson's JSON readers,
 * which abort on an allocation failure in their lexer (jansson issue 362:
 * lex_save drops strbuffer_append_byte's failure, then assert(0) or
 * assert(c == d)); everything our code does with what they return is
 * tested. */
void alloc_fail_pause(void);
void alloc_fail_resume(void);

/* The blocks that the last armed run allocated on its thread and that are
 * still allocated, each with its number in the run, its size and where it
 * was allocated (function names), printed to out; returns how many. */
long alloc_fail_report_leaks(FILE *out);

#endif
