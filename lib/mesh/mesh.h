/* mesh.h: triangle meshes of the workpiece and what to do with them. lib/mesh
 * turns the stock's level set (whole grid or dirty 64^3 chunks) and F-rep
 * fields into triangle meshes, encodes them (Draco, binary STL, binary PLY
 * with colours, OBJ) and renders them to PNG pictures without a display.
 * No C++ type crosses this header; the Draco and OpenVDB work happens in
 * C++ bridges behind it. */
#ifndef FM_MESH_H
#define FM_MESH_H

#include <stddef.h>
#include <stdint.h>

/* C linkage for the C++ bridges that implement part of this API (core.h
 * included inside, since it has no guard of its own). */
#ifdef __cplusplus
extern "C" {
#endif

#include "core/core.h"

struct fm_field;  /* frep/frep.h */
struct fm_stock;  /* stock/stock.h */
struct fm_design; /* stock/stock.h */

/* ---------------------------------------------------------------- mesh -- */

/* Attribute flags for fm_mesh_new. */
#define FM_MESH_NORMALS 1u
#define FM_MESH_COLORS 2u

/* Default budgets: 2^25 vertices (about 0.9 GB with normals and colours)
 * and 2^26 triangles. */
#define FM_MESH_DEFAULT_MAX_VERTICES ((size_t)1 << 25)
#define FM_MESH_DEFAULT_MAX_TRIANGLES ((size_t)1 << 26)

typedef struct fm_mesh_budget {
    size_t max_vertices;
    size_t max_triangles;
} fm_mesh_budget;

/* An indexed triangle mesh in millimetres. Triangles are counter-clockwise
 * seen from outside (right-hand normal points out of the solid). normals
 * (unit, per vertex) and colors (RGB, per vertex) are NULL when absent. The
 * arrays may be larger than the counts (capacity); only counts are valid. */
typedef struct fm_mesh {
    size_t vertex_count;
    size_t triangle_count;
    float *positions;    /* 3 * vertex_count */
    float *normals;      /* 3 * vertex_count or NULL */
    uint8_t *colors;     /* 3 * vertex_count or NULL */
    uint32_t *triangles; /* 3 * triangle_count */
    size_t vertex_capacity;
    size_t triangle_capacity;
    fm_mesh_budget budget;
} fm_mesh;

/* A mesh with room for the given counts (counts start at 0) and the given
 * attributes. budget may be NULL (defaults). FM_ERR_LIMIT if a count is
 * over the budget. */
fm_mesh *fm_mesh_new(size_t vertices, size_t triangles, unsigned attributes,
                     const fm_mesh_budget *budget, fm_error *err);
void fm_mesh_free(fm_mesh *mesh);
/* Grow capacity to at least the given counts (checked against the budget). */
fm_status fm_mesh_reserve(fm_mesh *mesh, size_t vertices, size_t triangles, fm_error *err);
/* Append a vertex (normal and rgb may be NULL when the mesh lacks them or
 * the caller fills them later) / a triangle. Return the new index, or
 * FM_ERR_LIMIT through err and (size_t)-1. */
size_t fm_mesh_add_vertex(fm_mesh *mesh, const float p[3], const float normal[3],
                          const uint8_t rgb[3], fm_error *err);
size_t fm_mesh_add_triangle(fm_mesh *mesh, uint32_t a, uint32_t b, uint32_t c, fm_error *err);
/* Append src to dst (indices shifted). Attributes dst has but src lacks are
 * zero-filled. */
fm_status fm_mesh_append(fm_mesh *dst, const fm_mesh *src, fm_error *err);
/* Add (or recompute) per-vertex normals: area-weighted face normals. */
fm_status fm_mesh_compute_normals(fm_mesh *mesh, fm_error *err);
/* Merge vertices with bit-identical positions (the first one's attributes
 * win) and drop triangles that become degenerate. */
fm_status fm_mesh_weld(fm_mesh *mesh, fm_error *err);
/* Axis-aligned bounds of the vertices; 0 if the mesh has none. */
int fm_mesh_bounds(const fm_mesh *mesh, float lo[3], float hi[3]);
/* Signed volume enclosed (mm^3): positive for a closed mesh oriented
 * outward. */
double fm_mesh_volume(const fm_mesh *mesh);

/* Edge topology of an indexed mesh, counted over undirected edges. */
typedef struct fm_mesh_topology {
    size_t edges;           /* distinct undirected edges */
    size_t boundary_edges;  /* used by one triangle */
    size_t nonmanifold_edges; /* used by three or more triangles */
    size_t misoriented_edges; /* used twice in the same direction */
    size_t degenerate_triangles; /* with a repeated vertex index */
} fm_mesh_topology;
/* Closed and consistently oriented when every count but edges is 0. */
fm_status fm_mesh_topology_check(const fm_mesh *mesh, fm_mesh_topology *out, fm_error *err);

/* ------------------------------------------------------------ encoders -- */

typedef enum fm_mesh_format {
    FM_MESH_FORMAT_UNKNOWN = 0,
    FM_MESH_FORMAT_DRACO, /* .drc */
    FM_MESH_FORMAT_STL,   /* .stl, binary */
    FM_MESH_FORMAT_PLY,   /* .ply, binary little-endian, with normals and colours */
    FM_MESH_FORMAT_OBJ    /* .obj, text, with normals ("v x y z r g b" colours) */
} fm_mesh_format;

/* The format a file name asks for by its extension (case-insensitive). */
fm_mesh_format fm_mesh_format_from_path(const char *path);

/* Draco options. Defaults (fm_mesh_draco_default, measured in
 * docs/mesh.md): 16 position bits, 8 normal bits, 8 colour bits, speed 5. */
typedef struct fm_mesh_draco_options {
    int position_bits;  /* 1..30: quantization of positions over the bounding cube */
    int normal_bits;    /* 1..30 */
    int color_bits;     /* 1..30; 8 keeps 8-bit colours exact */
    int speed;          /* 0 (smallest, slowest) .. 10 (fastest); encode and decode alike */
    int with_normals;   /* carry normals when the mesh has them */
    int with_colors;    /* carry colours when the mesh has them */
} fm_mesh_draco_options;
void fm_mesh_draco_default(fm_mesh_draco_options *opt);

/* The largest distance between an original vertex and its decoded position
 * for a mesh with these bounds at this many position bits: Draco quantizes
 * each coordinate to (2^bits - 1) steps over the largest extent, so the
 * error per coordinate is at most half a step. */
double fm_mesh_draco_error_bound(const float lo[3], const float hi[3], int position_bits);

/* Encoders into a malloc'd buffer (free it with free()). opt may be NULL
 * (defaults). */
fm_status fm_mesh_encode_draco(const fm_mesh *mesh, const fm_mesh_draco_options *opt,
                               uint8_t **out, size_t *size, fm_error *err);
fm_status fm_mesh_encode_stl(const fm_mesh *mesh, uint8_t **out, size_t *size, fm_error *err);
fm_status fm_mesh_encode_ply(const fm_mesh *mesh, uint8_t **out, size_t *size, fm_error *err);
fm_status fm_mesh_encode_obj(const fm_mesh *mesh, uint8_t **out, size_t *size, fm_error *err);

/* Decode a Draco mesh (positions, and normals and colours when present).
 * budget may be NULL. FM_ERR_INPUT for bytes that are not a Draco mesh. */
fm_mesh *fm_mesh_decode_draco(const uint8_t *data, size_t size, const fm_mesh_budget *budget,
                              fm_error *err);

/* Write in the format the extension names (.drc .stl .ply .obj). The file
 * is written whole to "<path>.tmp" and renamed, so a reader never sees half
 * a mesh. draco may be NULL. */
fm_status fm_mesh_write_file(const fm_mesh *mesh, const char *path,
                             const fm_mesh_draco_options *draco, fm_error *err);
fm_status fm_mesh_write_stl(const fm_mesh *mesh, const char *path, fm_error *err);
fm_status fm_mesh_write_ply(const fm_mesh *mesh, const char *path, fm_error *err);
fm_status fm_mesh_write_obj(const fm_mesh *mesh, const char *path, fm_error *err);
fm_status fm_mesh_write_draco(const fm_mesh *mesh, const fm_mesh_draco_options *opt,
                              const char *path, fm_error *err);

/* ------------------------------------------------------------ pictures -- */

/* A colour key drawn in the picture's top-left corner: count swatches top
 * to bottom, each with a label beside it, and a title above. Labels and
 * title are drawn with a small built-in font of digits, '+', '-', '.', 'm'
 * and spaces (other characters are left blank). */
#define FM_RENDER_LEGEND_MAX 16
typedef struct fm_render_legend {
    char title[16];
    size_t count;
    uint8_t colors[FM_RENDER_LEGEND_MAX][3];
    char labels[FM_RENDER_LEGEND_MAX][16];
} fm_render_legend;

/* A toolpath polyline for the overlay: count points (x, y, z in mm). */
typedef struct fm_render_polyline {
    const double *points; /* 3 * count */
    size_t count;
    int rapid; /* drawn dashed when set, solid otherwise */
} fm_render_polyline;

/* The view is isometric with Z up, looking from the direction (1, -1, 1)
 * (front, right and top faces visible): screen right is (1, 1, 0)/sqrt 2,
 * screen up is (-1, 1, 2)/sqrt 6. The projected bounding box of the mesh's
 * vertices and the polylines' points is scaled uniformly to fit the image
 * less margin pixels on every side, and centred. Pixel (px, py) has its
 * centre at (px + 0.5, py + 0.5), py counted from the top. */
typedef struct fm_render_options {
    int width, height;       /* pixels; default 800 x 600 */
    int margin;              /* pixels; default 16 */
    int antialias;           /* supersampling factor per axis 1..4; default 2 */
    uint8_t background[3];   /* default white */
    uint8_t base_color[3];   /* for meshes without colours; default light grey-blue */
    double light[3];         /* direction towards the light; default (0.3, -0.5, 1) */
    double ambient;          /* 0..1; shade = ambient + (1 - ambient) * max(0, n.l); default 0.25 */
    const fm_render_polyline *paths; /* toolpath overlay; may be NULL */
    size_t path_count;
    uint8_t feed_color[3];   /* default blue */
    uint8_t rapid_color[3];  /* default red */
    double dash_pixels;      /* dash and gap length of rapids; default 6 */
    const fm_render_legend *legend; /* colour key; may be NULL */
    /* The scene turned before it is viewed (3x3 row-major, x -> R x; NULL:
     * as it is), e.g. a workpiece in its position on a rotary table. The
     * view and light stay; a translation would not change a fitted picture. */
    const double *rotation;
} fm_render_options;
void fm_render_default(fm_render_options *opt);

/* Render into rgb (3 * width * height bytes, row-major from the top).
 * Meshes with normals are lit per pixel with the interpolated normal,
 * meshes without normals flat per triangle. */
fm_status fm_render_rgb(const fm_mesh *mesh, const fm_render_options *opt, uint8_t *rgb,
                        fm_error *err);
/* Render and write a PNG file (temporary file and rename). */
fm_status fm_render_png(const fm_mesh *mesh, const fm_render_options *opt, const char *path,
                        fm_error *err);

/* ---------------------------------------------------------- extraction -- */

typedef enum fm_mesh_coloring {
    FM_MESH_COLOR_NONE = 0,
    FM_MESH_COLOR_DEPTH, /* by depth below options.top_z: a ramp over [0, depth_range] */
    FM_MESH_COLOR_TOOL,  /* by the tool that last cut there (lib/stock's tool marks) */
    FM_MESH_COLOR_DEVIATION /* by the deviation from options.design (fm_mesh_deviation_color) */
} fm_mesh_coloring;

typedef struct fm_mesh_extract_options {
    double adaptivity;    /* OpenVDB volume-to-mesh adaptivity 0..1 (whole grid only); default 0 */
    int normals;          /* per-vertex normals from the level-set gradient; default 1 */
    fm_mesh_coloring coloring; /* default FM_MESH_COLOR_NONE */
    double top_z;         /* original stock top for FM_MESH_COLOR_DEPTH, mm */
    double depth_range;   /* mm of depth the ramp spans; default 10 */
    int uncut_grey;       /* FM_MESH_COLOR_DEPTH: where no cut reached, the uncut grey
                             (fm_mesh_tool_color(-1)) instead of the ramp; default 0 */
    const struct fm_design *design; /* FM_MESH_COLOR_DEVIATION: the design compared with */
    double deviation_range; /* mm of deviation the shades span; 0: 10 x the design's tolerance */
    fm_mesh_budget budget;
} fm_mesh_extract_options;
void fm_mesh_extract_default(fm_mesh_extract_options *opt);

/* Colour of a depth (mm below top) on the ramp FM_MESH_COLOR_DEPTH uses;
 * and of a tool number for FM_MESH_COLOR_TOOL: twelve distinct hues by
 * tool number modulo 12, and a neutral grey for tool < 0 (never cut). */
void fm_mesh_depth_color(double depth, double range, uint8_t rgb[3]);
void fm_mesh_tool_color(int tool, uint8_t rgb[3]);
/* Colour of a deviation from the design (mm; > 0 excess: material outside
 * the design; < 0 gouge: design material removed), Fusion's convention:
 * green within +-tolerance, blue for excess and red for gouge, light at
 * the tolerance and dark at range and beyond. */
void fm_mesh_deviation_color(double deviation, double tolerance, double range, uint8_t rgb[3]);
/* The key of that scale (title "mm"): seven swatches from +range (dark
 * blue) through 0 (green) to -range (dark red). */
void fm_mesh_deviation_legend(double tolerance, double range, fm_render_legend *legend);

/* The whole stock. opt may be NULL (defaults). */
fm_mesh *fm_mesh_from_stock(struct fm_stock *stock, const fm_mesh_extract_options *opt,
                            fm_error *err);
/* One 64^3-voxel chunk (index as in fm_stock_chunk). The chunk owns the
 * faces crossing the grid edges that start at its voxels, so chunk meshes
 * put side by side have no cracks and no overlaps, and welding their union
 * gives the whole-grid mesh at adaptivity 0. Returns an empty mesh for a
 * chunk without surface. Adaptivity is ignored (0). */
fm_mesh *fm_mesh_from_stock_chunk(struct fm_stock *stock, const int32_t chunk[3],
                                  const fm_mesh_extract_options *opt, fm_error *err);

/* What fm_mesh_from_stock_chunk_cached keeps of one chunk between calls:
 * its faces per 8^3 leaf and a hash of each leaf's values. Owned by the
 * caller; one chunk per cache (another chunk index or other options mesh
 * the chunk whole and cache it anew). */
typedef struct fm_mesh_chunk_cache fm_mesh_chunk_cache;
fm_mesh_chunk_cache *fm_mesh_chunk_cache_new(void); /* NULL: out of memory */
void fm_mesh_chunk_cache_free(fm_mesh_chunk_cache *cache);
/* The same mesh as fm_mesh_from_stock_chunk (the same triangles, vertices
 * shared between triangles welded; their order differs), remeshing only
 * the leaves whose values changed since the cache's last call and their
 * neighbours; the rest comes from the cache. cache NULL: no cache. */
fm_mesh *fm_mesh_from_stock_chunk_cached(struct fm_stock *stock, const int32_t chunk[3],
                                         const fm_mesh_extract_options *opt,
                                         fm_mesh_chunk_cache *cache, fm_error *err);
/* Leaves the last call remeshed (512 for a whole chunk; 0: all reused). */
size_t fm_mesh_chunk_cache_last_leaves(const fm_mesh_chunk_cache *cache);

/* Mesh an F-rep field (positive inside; frep.h's fm_field, bounds included)
 * by rasterizing it with lib/stock's narrow-band rasterizer at voxel_mm and
 * meshing the whole grid. */
fm_mesh *fm_mesh_from_field(const struct fm_field *field, double voxel_mm,
                            const fm_mesh_extract_options *opt, fm_error *err);

#ifdef __cplusplus
}
#endif

#endif
