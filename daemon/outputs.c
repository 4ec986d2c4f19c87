/* outputs.c: the final stock to files, by extension: .vdb snapshots through
 * lib/stock, meshes through lib/mesh (whole-grid extraction, coloured by
 * the tool that cut last when the stock tracks it). */
#include "outputs.h"

#include <ctype.h>
#include <string.h>

#include "mesh/mesh.h"

static int ends_with(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    if (n <= e) return 0;
    for (size_t i = 0; i < e; i++)
        if (tolower((unsigned char)path[n - e + i]) != ext[i]) return 0;
    return 1;
}

const char *fm_output_formats(void)
{
    return ".vdb, .drc, .stl, .ply, .obj";
}

int fm_output_format_known(const char *path)
{
    return ends_with(path, ".vdb") || fm_mesh_format_from_path(path) != FM_MESH_FORMAT_UNKNOWN;
}

fm_status fm_output_write(const char *path, fm_stock *stock, fm_error *err)
{
    if (ends_with(path, ".vdb")) return fm_stock_save(stock, path, NULL, err);
    if (fm_mesh_format_from_path(path) == FM_MESH_FORMAT_UNKNOWN)
        return fm_error_set(err, FM_ERR_INPUT, "%s: unknown output format (use %s)", path,
                            fm_output_formats());
    fm_mesh_extract_options opt;
    fm_mesh_extract_default(&opt);
    fm_mesh *mesh = fm_mesh_from_stock(stock, &opt, err);
    if (!mesh) return err ? err->code : FM_ERR_INTERNAL;
    fm_status st = fm_mesh_write_file(mesh, path, NULL, err);
    fm_mesh_free(mesh);
    return st;
}
