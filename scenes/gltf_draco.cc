// gltf_draco.cc - KHR_draco_mesh_compression: a primitive's Draco bitstream
// decoded into triangles and per-vertex attribute values (the Draco library
// is C++; this exposes one C function to the glTF adapter). Without Draco at
// build time (meson found no libdraco) it says so.
#include <cstring>
#include <string>

extern "C" {
#include "gltf_draco.h"
}

#if SB_HAVE_DRACO
#include <draco/compression/decode.h>
#include <draco/mesh/mesh.h>

extern "C" bool sb_draco_decode(const unsigned char *data, size_t len, const int *ids, const int *ncomp, int nattr,
                                sb_draco_out *out, char *why, size_t why_len) {
    memset(out, 0, sizeof *out);
    try {
        draco::DecoderBuffer buf;
        buf.Init(reinterpret_cast<const char *>(data), len);
        draco::Decoder dec;
        auto res = dec.DecodeMeshFromBuffer(&buf);
        if (!res.ok()) return snprintf(why, why_len, "Draco: %s", res.status().error_msg()), false;
        std::unique_ptr<draco::Mesh> mesh = std::move(res).value();
        out->points = mesh->num_points();
        out->index_count = (size_t)mesh->num_faces() * 3;
        out->indices = static_cast<uint32_t *>(sb_xmalloc(sizeof(uint32_t) * (out->index_count ? out->index_count : 1)));
        for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f)
            for (int k = 0; k < 3; k++) out->indices[3 * f.value() + k] = mesh->face(f)[k].value();
        for (int a = 0; a < nattr && a < SB_DRACO_MAX_ATTRS; a++) {
            const draco::PointAttribute *att = mesh->GetAttributeByUniqueId((uint32_t)ids[a]);
            if (!att) return snprintf(why, why_len, "Draco: the bitstream has no attribute with id %d", ids[a]), false;
            double *v = static_cast<double *>(sb_xmalloc(sizeof(double) * (size_t)ncomp[a] * (out->points ? out->points : 1)));
            out->values[a] = v;
            float tmp[16] = {0};
            for (draco::PointIndex p(0); p < mesh->num_points(); ++p) {
                if (!att->ConvertValue<float>(att->mapped_index(p), (int8_t)ncomp[a], tmp))
                    return snprintf(why, why_len, "Draco: attribute %d cannot be read as %d floats", ids[a], ncomp[a]),
                           false;
                for (int k = 0; k < ncomp[a]; k++) v[(size_t)p.value() * ncomp[a] + k] = tmp[k];
            }
        }
        return true;
    } catch (const std::exception &ex) {
        return snprintf(why, why_len, "Draco: %s", ex.what()), false;
    }
}

#else

extern "C" bool sb_draco_decode(const unsigned char *, size_t, const int *, const int *, int, sb_draco_out *out,
                                char *why, size_t why_len) {
    memset(out, 0, sizeof *out);
    snprintf(why, why_len, "KHR_draco_mesh_compression: this shadowbench was built without Draco (libdraco-dev)");
    return false;
}

#endif

extern "C" void sb_draco_free(sb_draco_out *out) {
    free(out->indices);
    for (int a = 0; a < SB_DRACO_MAX_ATTRS; a++) free(out->values[a]);
    memset(out, 0, sizeof *out);
}
