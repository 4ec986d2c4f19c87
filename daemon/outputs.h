/* outputs.h: writing a job's final stock in the format its file name asks
 * for: a frepmill .vdb snapshot, or a mesh (.drc, .stl, .ply, .obj). */
#ifndef FM_OUTPUTS_H
#define FM_OUTPUTS_H

#include "core/core.h"
#include "stock/stock.h"

/* "a, b, c" list of the extensions understood, for messages. */
const char *fm_output_formats(void);
int fm_output_format_known(const char *path);
fm_status fm_output_write(const char *path, fm_stock *stock, fm_error *err);

#endif
