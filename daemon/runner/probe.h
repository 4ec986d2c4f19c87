/* probe.h: simulated probing for the runner (G38.2-G38.5): where a tool
 * moving along a straight segment first touches the stock (or a fixture of
 * the collision check), or first leaves it. Private to daemon/runner
 * (job.c answers the G-code interpreter's probe callback with it). */
#ifndef FM_RUNNER_PROBE_H
#define FM_RUNNER_PROBE_H

#include "check/check.h"
#include "core/core.h"
#include "stock/stock.h"
#include "tools/tools.h"

/* The tool tip moves from tip_start to tip_end (machine mm). toward = 1:
 * find the first position where the tool touches the stock or, when
 * fixtures is not NULL, one of the collision check's fixtures
 * (G38.2/G38.3); toward = 0: the first position where it touches neither
 * (G38.4/G38.5). *tripped = 1 and *fraction (0..1 along the move) when
 * that happens; *at_start = 1 when the tool is already in that state at
 * the start. tool may be NULL (a point probe at the tip). The search
 * marches by the distance of the stock and fixtures and bisects to 1e-6
 * mm; the tool's surface is sampled at half the stock's voxel, so a
 * feature thinner than that between samples may be missed. */
fm_status fm_runner_probe(const fm_stock *stock, const fm_check *fixtures, const fm_tool *tool,
                          const double tip_start[3], const double tip_end[3], int toward,
                          int *tripped, double *fraction, int *at_start, fm_error *err);

#endif
