// glb_draco.cc - Draco compression of a mesh for the scene writer (glb.h):
// the conformance set's Draco-compressed copy of a bundled scene. Without
// Draco at build time it reports failure (scenegen then skips that scene).
#include <cstdlib>
#include <cstring>

extern "C" {
#include "glb.h"
}

#if SB_HAVE_DRACO
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

extern "C" bool sb_glb_draco_encode(const float *pos, const float *nrm, uint32_t nv, const uint32_t *idx, uint32_t ni,
                                    unsigned char **out, size_t *len, int *pos_id, int *nrm_id) {
    draco::Mesh mesh;
    mesh.set_num_points(nv);
    int att[2];
    const float *src[2] = {pos, nrm};
    for (int a = 0; a < 2; a++) {
        draco::GeometryAttribute ga;
        ga.Init(a ? draco::GeometryAttribute::NORMAL : draco::GeometryAttribute::POSITION, nullptr, 3,
                draco::DT_FLOAT32, false, sizeof(float) * 3, 0);
        att[a] = mesh.AddAttribute(ga, true, nv);
        for (uint32_t v = 0; v < nv; v++)
            mesh.attribute(att[a])->SetAttributeValue(draco::AttributeValueIndex(v), src[a] + 3 * (size_t)v);
    }
    for (uint32_t t = 0; t + 2 < ni; t += 3)
        mesh.AddFace({draco::PointIndex(idx[t]), draco::PointIndex(idx[t + 1]), draco::PointIndex(idx[t + 2])});
    draco::Encoder enc; // no quantization: the positions come back bit for bit
    enc.SetSpeedOptions(5, 5);
    draco::EncoderBuffer buf;
    if (!enc.EncodeMeshToBuffer(mesh, &buf).ok()) return false;
    *len = buf.size();
    *out = static_cast<unsigned char *>(malloc(buf.size() ? buf.size() : 1));
    if (!*out) return false;
    memcpy(*out, buf.data(), buf.size());
    *pos_id = (int)mesh.attribute(att[0])->unique_id();
    *nrm_id = (int)mesh.attribute(att[1])->unique_id();
    return true;
}

#else

extern "C" bool sb_glb_draco_encode(const float *, const float *, uint32_t, const uint32_t *, uint32_t,
                                    unsigned char **, size_t *, int *, int *) {
    return false;
}

#endif
