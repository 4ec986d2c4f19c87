// draco_bridge.cpp: the only file that sees Draco. Encodes an fm_mesh
// (positions, optional normals and colours) to a Draco bitstream and decodes
// one back, exporting a C API (mesh.h). Every exception stops here and
// becomes an fm_status.
#include "mesh/mesh.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <new>

namespace {

// Adds a per-vertex attribute with identity mapping and copies the values in.
int add_attribute(draco::Mesh &dm, draco::GeometryAttribute::Type type, draco::DataType dt,
                  bool normalized, int components, size_t elem_size, const void *values,
                  size_t count)
{
    draco::GeometryAttribute ga;
    ga.Init(type, nullptr, static_cast<uint8_t>(components), dt, normalized,
            static_cast<int64_t>(elem_size * components), 0);
    int id = dm.AddAttribute(ga, true, static_cast<uint32_t>(count));
    if (id < 0)
        return id;
    draco::PointAttribute *pa = dm.attribute(id);
    const uint8_t *p = static_cast<const uint8_t *>(values);
    for (size_t i = 0; i < count; i++)
        pa->SetAttributeValue(draco::AttributeValueIndex(static_cast<uint32_t>(i)),
                              p + i * elem_size * components);
    return id;
}

bool bits_ok(int b) { return b >= 1 && b <= 30; }

fm_status encode(const fm_mesh *mesh, const fm_mesh_draco_options *opt, uint8_t **out,
                 size_t *size, fm_error *err)
{
    fm_mesh_draco_options o;
    if (opt)
        o = *opt;
    else
        fm_mesh_draco_default(&o);
    if (!bits_ok(o.position_bits) || !bits_ok(o.normal_bits) || !bits_ok(o.color_bits))
        return fm_error_set(err, FM_ERR_INPUT, "Draco quantization bits must be 1..30");
    if (o.speed < 0 || o.speed > 10)
        return fm_error_set(err, FM_ERR_INPUT, "Draco speed must be 0..10, not %d", o.speed);
    if (mesh->vertex_count > UINT32_MAX / 2 || mesh->triangle_count > UINT32_MAX / 2)
        return fm_error_set(err, FM_ERR_LIMIT, "mesh too large for Draco");

    draco::Mesh dm;
    dm.set_num_points(static_cast<uint32_t>(mesh->vertex_count));
    if (add_attribute(dm, draco::GeometryAttribute::POSITION, draco::DT_FLOAT32, false, 3,
                      sizeof(float), mesh->positions, mesh->vertex_count) < 0)
        return fm_error_set(err, FM_ERR_INTERNAL, "Draco refused the position attribute");
    if (o.with_normals && mesh->normals &&
        add_attribute(dm, draco::GeometryAttribute::NORMAL, draco::DT_FLOAT32, false, 3,
                      sizeof(float), mesh->normals, mesh->vertex_count) < 0)
        return fm_error_set(err, FM_ERR_INTERNAL, "Draco refused the normal attribute");
    if (o.with_colors && mesh->colors &&
        add_attribute(dm, draco::GeometryAttribute::COLOR, draco::DT_UINT8, true, 3, 1,
                      mesh->colors, mesh->vertex_count) < 0)
        return fm_error_set(err, FM_ERR_INTERNAL, "Draco refused the colour attribute");
    dm.SetNumFaces(mesh->triangle_count);
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        draco::Mesh::Face f;
        for (int k = 0; k < 3; k++)
            f[k] = draco::PointIndex(mesh->triangles[3 * t + k]);
        dm.SetFace(draco::FaceIndex(static_cast<uint32_t>(t)), f);
    }

    draco::Encoder enc;
    enc.SetAttributeQuantization(draco::GeometryAttribute::POSITION, o.position_bits);
    enc.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, o.normal_bits);
    enc.SetAttributeQuantization(draco::GeometryAttribute::COLOR, o.color_bits);
    enc.SetSpeedOptions(o.speed, o.speed);
    draco::EncoderBuffer buf;
    draco::Status s = enc.EncodeMeshToBuffer(dm, &buf);
    if (!s.ok())
        return fm_error_set(err, FM_ERR_INTERNAL, "Draco encoding failed: %s",
                            s.error_msg_string().c_str());
    uint8_t *data = static_cast<uint8_t *>(std::malloc(buf.size() ? buf.size() : 1));
    if (!data)
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory for a Draco buffer");
    std::memcpy(data, buf.data(), buf.size());
    *out = data;
    *size = buf.size();
    return FM_OK;
}

fm_mesh *decode(const uint8_t *data, size_t size, const fm_mesh_budget *budget, fm_error *err)
{
    draco::DecoderBuffer db;
    db.Init(reinterpret_cast<const char *>(data), size);
    auto type = draco::Decoder::GetEncodedGeometryType(&db);
    if (!type.ok() || type.value() != draco::TRIANGULAR_MESH) {
        fm_error_set(err, FM_ERR_INPUT, "not a Draco triangle mesh");
        return nullptr;
    }
    draco::Decoder dec;
    auto res = dec.DecodeMeshFromBuffer(&db);
    if (!res.ok()) {
        fm_error_set(err, FM_ERR_INPUT, "Draco decoding failed: %s",
                     res.status().error_msg_string().c_str());
        return nullptr;
    }
    std::unique_ptr<draco::Mesh> dm = std::move(res).value();
    const draco::PointAttribute *pos =
        dm->GetNamedAttribute(draco::GeometryAttribute::POSITION);
    if (!pos || pos->num_components() != 3) {
        fm_error_set(err, FM_ERR_INPUT, "Draco mesh without 3D positions");
        return nullptr;
    }
    const draco::PointAttribute *nor = dm->GetNamedAttribute(draco::GeometryAttribute::NORMAL);
    const draco::PointAttribute *col = dm->GetNamedAttribute(draco::GeometryAttribute::COLOR);
    if (nor && nor->num_components() != 3)
        nor = nullptr;
    if (col && col->num_components() < 3)
        col = nullptr;
    size_t nv = dm->num_points(), nt = dm->num_faces();
    unsigned attrs = (nor ? FM_MESH_NORMALS : 0u) | (col ? FM_MESH_COLORS : 0u);
    fm_mesh *m = fm_mesh_new(nv, nt, attrs, budget, err);
    if (!m)
        return nullptr;
    // Frees the mesh if anything below throws.
    std::unique_ptr<fm_mesh, void (*)(fm_mesh *)> guard(m, fm_mesh_free);
    for (uint32_t i = 0; i < nv; i++) {
        draco::PointIndex pi(i);
        float p[3] = {0, 0, 0};
        pos->ConvertValue<float>(pos->mapped_index(pi), 3, p);
        std::memcpy(m->positions + 3 * i, p, sizeof p);
        if (nor) {
            float n[3] = {0, 0, 0};
            nor->ConvertValue<float>(nor->mapped_index(pi), 3, n);
            std::memcpy(m->normals + 3 * i, n, sizeof n);
        }
        if (col) {
            uint8_t c[4] = {0, 0, 0, 0};
            col->ConvertValue<uint8_t>(col->mapped_index(pi), 3, c);
            std::memcpy(m->colors + 3 * i, c, 3);
        }
    }
    for (uint32_t t = 0; t < nt; t++) {
        const draco::Mesh::Face &f = dm->face(draco::FaceIndex(t));
        for (int k = 0; k < 3; k++) {
            uint32_t v = f[k].value();
            if (v >= nv) {
                fm_error_set(err, FM_ERR_INPUT, "Draco mesh refers to a missing vertex");
                return nullptr;
            }
            m->triangles[3 * t + k] = v;
        }
    }
    m->vertex_count = nv;
    m->triangle_count = nt;
    return guard.release();
}

} // namespace

extern "C" {

void fm_mesh_draco_default(fm_mesh_draco_options *opt)
{
    // Chosen by the measurement in docs/mesh.md.
    opt->position_bits = 16;
    opt->normal_bits = 8;
    opt->color_bits = 8;
    opt->speed = 5;
    opt->with_normals = 1;
    opt->with_colors = 1;
}

double fm_mesh_draco_error_bound(const float lo[3], const float hi[3], int position_bits)
{
    double range = 0, mag = 0;
    for (int k = 0; k < 3; k++) {
        range = std::fmax(range, static_cast<double>(hi[k]) - lo[k]);
        mag = std::fmax(mag, std::fmax(std::fabs(lo[k]), std::fabs(hi[k])));
    }
    if (range <= 0)
        range = 1; // Draco's own choice for a flat range
    double steps = std::ldexp(1.0, position_bits) - 1.0;
    // Half a step per coordinate, plus the float rounding of Draco's
    // single-precision dequantization (a few ulps of the coordinates).
    double per_axis = 0.5 * range / steps + 4.0 * FLT_EPSILON * (mag + range);
    return std::sqrt(3.0) * per_axis;
}

fm_status fm_mesh_encode_draco(const fm_mesh *mesh, const fm_mesh_draco_options *opt,
                               uint8_t **out, size_t *size, fm_error *err)
{
    try {
        return encode(mesh, opt, out, size, err);
    } catch (const std::bad_alloc &) {
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory in Draco encoding");
    } catch (const std::exception &e) {
        return fm_error_set(err, FM_ERR_INTERNAL, "Draco encoding: %s", e.what());
    } catch (...) {
        return fm_error_set(err, FM_ERR_INTERNAL, "Draco encoding: unknown exception");
    }
}

fm_mesh *fm_mesh_decode_draco(const uint8_t *data, size_t size, const fm_mesh_budget *budget,
                              fm_error *err)
{
    try {
        return decode(data, size, budget, err);
    } catch (const std::bad_alloc &) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory in Draco decoding");
    } catch (const std::exception &e) {
        fm_error_set(err, FM_ERR_INTERNAL, "Draco decoding: %s", e.what());
    } catch (...) {
        fm_error_set(err, FM_ERR_INTERNAL, "Draco decoding: unknown exception");
    }
    return nullptr;
}

} // extern "C"
