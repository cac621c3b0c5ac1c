// gltf_load.cc - the tinygltf adapter: glTF 2.0 (.gltf/.glb) into the flat C
// scene model, and animated glTF cameras into paths. The only C++ on the
// scene side besides the Draco decoder; everything it exposes is a C function.
//
// What it applies (README "glTF features"): node transforms (posed at --pose T
// from the first animation), skins (vertices skinned on the CPU, the same
// triangles for the rasterizer and the rays), morph targets at their default
// weights, EXT_mesh_gpu_instancing (expanded), KHR_mesh_quantization and sparse
// accessors (any component type), KHR_draco_mesh_compression, materials'
// doubleSided and alpha (MASK, BLEND under --blend-casters) with the alpha of
// the base-colour texture (decoded only for such materials) and
// KHR_texture_transform.
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>
#include <algorithm>

#include <tiny_gltf.h>

#include "motion_data.h"

extern "C" {
#include "anim.h"
#include "gltf_check.h"
#include "gltf_draco.h"
#include "gltf_load.h"
#include "motion.h"
#include "scene.h"
#include "scene_cache.h"
}

namespace {

using sbm::Channel;
using sbm::MoChannel;
using sbm::MoClip;
using sbm::MoPlace;
using sbm::PrimData;
using sbm::normal_matrix;
using sbm::skin_vertices;
using sbm::PATH_R;
using sbm::PATH_S;
using sbm::PATH_T;
using sbm::PATH_W;

// Images are kept encoded as they are read; only the ones an alpha test needs
// are decoded afterwards (shadows need no other texture).
struct ImageStore {
    std::map<int, std::vector<unsigned char>> bytes;
    std::map<int, std::string> unread;   // an image an alpha test needs that could not be read: why
    std::string first_cause;             // the first alpha texture that cannot be used: where and why
};

// What the model's buffers are: each buffer's bytes, in the file as it is
// mapped (a .glb's BIN chunk: not copied) or in vectors of their own (data:
// URIs, files); alive while the model is read.
struct Document {
    void *map = nullptr;
    size_t map_len = 0;
    std::vector<std::vector<unsigned char>> owned;
    std::vector<std::pair<const unsigned char *, size_t>> bufs;
    Document() = default;
    Document(const Document &) = delete;
    Document &operator=(const Document &) = delete;
    ~Document() { sb_unmap_file(map, map_len); }
};

struct Ctx {
    const char *file;
    const tinygltf::Model *m;
    const Document *doc;
    sb_err *err;
    bool fail(const std::string &where, const std::string &what) {
        sb_fail(err, "%s: %s: %s", file, where.c_str(), what.c_str());
        return false;
    }
};

// Overflow-safe range test: [off, off + len) inside [0, size).
bool fits(size_t off, size_t len, size_t size) { return off <= size && len <= size - off; }

// A strided run of `count` elements of `elem` bytes at `off` in bufferView `view`;
// every range is checked again here (sb_gltf_check did it on the raw JSON).
bool view_range(Ctx &c, int view, size_t off, size_t count, size_t elem, size_t stride, const std::string &where,
                const unsigned char **data) {
    const tinygltf::Model &m = *c.m;
    if (view < 0 || view >= (int)m.bufferViews.size()) return c.fail(where + "/bufferView", "missing or out of range");
    const tinygltf::BufferView &bv = m.bufferViews[view];
    if (bv.buffer < 0 || bv.buffer >= (int)c.doc->bufs.size())
        return c.fail("/bufferViews/" + std::to_string(view) + "/buffer", "missing or out of range");
    const std::pair<const unsigned char *, size_t> &b = c.doc->bufs[bv.buffer];
    if (!fits(bv.byteOffset, bv.byteLength, b.second))
        return c.fail("/bufferViews/" + std::to_string(view), "range exceeds buffer " + std::to_string(bv.buffer) +
                                                                 " of " + std::to_string(b.second) + " bytes");
    size_t need;
    if (count == 0 || __builtin_mul_overflow(stride, count - 1, &need) || __builtin_add_overflow(need, elem, &need) ||
        !fits(off, need, bv.byteLength))
        return c.fail(where, "count " + std::to_string(count) + " runs past the end of bufferView " + std::to_string(view));
    *data = b.first + bv.byteOffset + off;
    return true;
}

// One component as a double: integers exactly, normalized ones mapped to [0, 1] or [-1, 1].
double component(const unsigned char *p, int ctype, bool normalized) {
    switch (ctype) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: { int8_t v; memcpy(&v, p, 1); return normalized ? std::max(v / 127.0, -1.0) : v; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t v; memcpy(&v, p, 2); return normalized ? std::max(v / 32767.0, -1.0) : v; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t v; memcpy(&v, p, 2); return normalized ? v / 65535.0 : v; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: { uint32_t v; memcpy(&v, p, 4); return v; }
    default: { float v; memcpy(&v, p, 4); return v; }
    }
}

// The sparse substitutions of an accessor, applied to out (count x ncomp, elem bytes each).
bool apply_sparse(Ctx &c, const tinygltf::Accessor &a, const std::string &ap, size_t elem,
                  const std::function<void(const unsigned char *, size_t)> &decode_one) {
    const auto &sp = a.sparse;
    std::string sp_path = ap + "/sparse";
    if (sp.count <= 0 || (size_t)sp.count > a.count || sp.indices.byteOffset < 0 || sp.values.byteOffset < 0)
        return c.fail(sp_path, "count or byteOffset out of range");
    int isize = tinygltf::GetComponentSizeInBytes(sp.indices.componentType);
    int ict = sp.indices.componentType;
    if (ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        return c.fail(sp_path + "/indices/componentType", "expected unsigned byte, short or int");
    const unsigned char *di, *dv;
    if (!view_range(c, sp.indices.bufferView, (size_t)sp.indices.byteOffset, (size_t)sp.count, (size_t)isize,
                    (size_t)isize, sp_path + "/indices", &di) ||
        !view_range(c, sp.values.bufferView, (size_t)sp.values.byteOffset, (size_t)sp.count, elem, elem,
                    sp_path + "/values", &dv))
        return false;
    size_t prev = 0;
    for (int k = 0; k < sp.count; k++) {
        size_t idx = (size_t)component(di + (size_t)k * isize, sp.indices.componentType, false);
        if (idx >= a.count || (k > 0 && idx <= prev))
            return c.fail(sp_path + "/indices", "index " + std::to_string(idx) + " at " + std::to_string(k) +
                                                     " is out of range or not increasing");
        decode_one(dv + (size_t)k * elem, idx);
        prev = idx;
    }
    return true;
}

// Reads accessor `acc` as count x ncomp doubles (any component type; matrix
// columns padded to 4 bytes as the spec lays them out; sparse values applied).
bool read_accessor(Ctx &c, int acc, const std::string &where, int want_type, std::vector<double> &out) {
    const tinygltf::Model &m = *c.m;
    if (acc < 0 || acc >= (int)m.accessors.size())
        return c.fail(where, "accessor " + std::to_string(acc) + " does not exist");
    const tinygltf::Accessor &a = m.accessors[acc];
    std::string ap = "/accessors/" + std::to_string(acc);
    if (want_type && a.type != want_type) return c.fail(ap, "unexpected accessor type");
    int csize = tinygltf::GetComponentSizeInBytes(a.componentType);
    int ncomp = tinygltf::GetNumComponentsInType(a.type);
    if (csize <= 0 || ncomp <= 0) return c.fail(ap, "invalid componentType or type");
    int rows = a.type == TINYGLTF_TYPE_MAT2 ? 2 : a.type == TINYGLTF_TYPE_MAT3 ? 3 : a.type == TINYGLTF_TYPE_MAT4 ? 4 : ncomp;
    size_t col = (size_t)rows * csize;
    if (rows != ncomp) col = (col + 3) / 4 * 4;   // matrix columns start on 4-byte boundaries
    size_t elem = col * (size_t)(ncomp / rows);
    size_t total;
    if (__builtin_mul_overflow(a.count, (size_t)ncomp, &total) || total > ((size_t)1 << 32))
        return c.fail(ap + "/count", std::to_string(a.count) + " elements are more than shadowbench reads");
    bool contiguous_floats = a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT && rows == ncomp && !a.sparse.isSparse &&
                             a.bufferView >= 0 && a.bufferView < (int)m.bufferViews.size() &&
                             (m.bufferViews[a.bufferView].byteStride == 0 || m.bufferViews[a.bufferView].byteStride == elem);
    const unsigned char *d0 = nullptr;
    if (contiguous_floats && !view_range(c, a.bufferView, a.byteOffset, a.count, elem, elem, ap, &d0)) return false;
    // the common case: converted as they come, without a pass of zeros first. The check sees to 4-byte alignment
    // for the accessors it checks; one only an extension reads (EXT_mesh_gpu_instancing) may sit anywhere
    if (contiguous_floats && reinterpret_cast<uintptr_t>(d0) % alignof(float) == 0) {
        const float *f = reinterpret_cast<const float *>(d0);
        out.assign(f, f + total);
        return true;
    }
    out.assign(total, 0.0);
    bool plain_floats = a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT && rows == ncomp;   // no matrix padding
    auto decode = [&](const unsigned char *d, size_t stride, size_t n, size_t first) {
        double *o = out.data() + first * ncomp;
        if (plain_floats) { // the common case, without a call per component
            for (size_t i = 0; i < n; i++, d += stride)
                for (int k = 0; k < ncomp; k++) {
                    float f;
                    memcpy(&f, d + 4 * k, 4);
                    *o++ = f;
                }
            return;
        }
        for (size_t i = 0; i < n; i++)
            for (int k = 0; k < ncomp; k++)
                *o++ = component(d + i * stride + (size_t)(k / rows) * col + (size_t)(k % rows) * csize, a.componentType,
                                 a.normalized);
    };
    if (a.bufferView >= (int)m.bufferViews.size()) return c.fail(ap + "/bufferView", "out of range");
    if (a.bufferView >= 0) {
        const unsigned char *d;
        size_t bs = m.bufferViews[a.bufferView].byteStride;
        size_t stride = bs ? bs : elem;
        if (stride < elem) return c.fail(ap, "byteStride is smaller than the element");
        if (!view_range(c, a.bufferView, a.byteOffset, a.count, elem, stride, ap, &d)) return false;
        decode(d, stride, a.count, 0);
    }
    if (a.sparse.isSparse)
        return apply_sparse(c, a, ap, elem, [&](const unsigned char *d, size_t idx) { decode(d, elem, 1, idx); });
    return true;
}

bool finite_all(Ctx &c, const std::string &where, const std::vector<double> &v, int ncomp) {
    for (size_t i = 0; i < v.size(); i++)
        if (!std::isfinite(v[i]))
            return c.fail(where, "element " + std::to_string(i / ncomp) + " is " + (std::isnan(v[i]) ? "NaN" : "Inf"));
    return true;
}

bool read_vec(Ctx &c, int acc, const std::string &where, int ncomp, std::vector<double> &out) {
    int type = ncomp == 1 ? TINYGLTF_TYPE_SCALAR : ncomp == 2 ? TINYGLTF_TYPE_VEC2 : ncomp == 3 ? TINYGLTF_TYPE_VEC3
             : ncomp == 4 ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_MAT4;
    return read_accessor(c, acc, where, type, out) && finite_all(c, where, out, ncomp);
}

bool read_indices(Ctx &c, int acc, const std::string &where, std::vector<uint32_t> &out) {
    const tinygltf::Model &m = *c.m;
    if (acc >= 0 && acc < (int)m.accessors.size()) { // the common case: packed unsigned integers, read as they are
        const tinygltf::Accessor &a = m.accessors[acc];
        int csize = a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT     ? 4
                    : a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 2
                    : a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE  ? 1
                                                                                : 0;
        if (csize && a.type == TINYGLTF_TYPE_SCALAR && !a.sparse.isSparse && a.bufferView >= 0 &&
            a.bufferView < (int)m.bufferViews.size() &&
            (m.bufferViews[a.bufferView].byteStride == 0 || m.bufferViews[a.bufferView].byteStride == (size_t)csize) &&
            a.count <= ((size_t)1 << 32)) {
            const unsigned char *d;
            std::string ap = "/accessors/" + std::to_string(acc);
            if (!view_range(c, a.bufferView, a.byteOffset, a.count, (size_t)csize, (size_t)csize, ap, &d)) return false;
            out.resize(a.count);
            if (csize == 4) memcpy(out.data(), d, a.count * 4);
            else if (csize == 2)
                for (size_t i = 0; i < a.count; i++) {
                    uint16_t x;
                    memcpy(&x, d + 2 * i, 2);
                    out[i] = x;
                }
            else
                for (size_t i = 0; i < a.count; i++) out[i] = d[i];
            return true;
        }
    }
    std::vector<double> v;
    if (!read_accessor(c, acc, where, TINYGLTF_TYPE_SCALAR, v)) return false;
    int ct = c.m->accessors[acc].componentType;
    if (ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        return c.fail(where, "indices must be unsigned byte, short or int");
    out.resize(v.size());
    for (size_t i = 0; i < v.size(); i++) out[i] = (uint32_t)v[i];
    return true;
}

sb_trs node_trs(const tinygltf::Node &n) {
    sb_trs x = {{0, 0, 0}, {0, 0, 0, 1}, {1, 1, 1}};
    for (size_t k = 0; k < 3 && n.translation.size() == 3; k++) x.t[k] = n.translation[k];
    for (size_t k = 0; k < 4 && n.rotation.size() == 4; k++) x.r[k] = n.rotation[k];
    for (size_t k = 0; k < 3 && n.scale.size() == 3; k++) x.s[k] = n.scale[k];
    return x;
}

sb_m4 node_local(const tinygltf::Node &n) {
    if (n.matrix.size() != 16) {
        sb_trs x = node_trs(n);
        return sb_trs_matrix(&x);
    }
    sb_m4 r;
    for (int i = 0; i < 16; i++) r.m[i] = n.matrix[i];
    return r;
}

double det3(const sb_m4 &w) {
    return w.m[0] * (w.m[5] * w.m[10] - w.m[9] * w.m[6]) - w.m[4] * (w.m[1] * w.m[10] - w.m[9] * w.m[2]) +
           w.m[8] * (w.m[1] * w.m[6] - w.m[5] * w.m[2]);
}


// One animation channel read into a sampler (its arrays kept alive by the owner).

// A channel the tool cannot play as written (key times that do not increase, which exported files carry; an
// output count that does not match the input's) is not an error of the file: *skip says why, and it is left
// out (said in info and in every run's warnings). References out of range stay errors.
bool read_channel(Ctx &c, const tinygltf::Animation &an, const tinygltf::AnimationChannel &ch, const std::string &where,
                  int ncomp, Channel &dst, std::string *skip) {
    skip->clear();
    if (ch.sampler < 0 || ch.sampler >= (int)an.samplers.size()) return c.fail(where, "sampler out of range");
    const auto &smp = an.samplers[ch.sampler];
    if (smp.input >= 0 && smp.input < (int)c.m->accessors.size() &&
        c.m->accessors[smp.input].componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
        return c.fail(where + "/input", "key times must be floats (glTF 2.0: an animation sampler's input is FLOAT; "
                                        "integers would be read as seconds)");
    if (!read_vec(c, smp.input, where + "/input", 1, dst.in)) return false;
    if (!read_accessor(c, smp.output, where + "/output", 0, dst.out) || !finite_all(c, where + "/output", dst.out, 1))
        return false;
    for (size_t i = 0; i < dst.out.size(); i++)   // a key no pose can hold (the posed bound: Loader::anim_bound)
        if (fabs(dst.out[i]) > SB_SCENE_MAX_COORD)
        {
            char what[160];
            snprintf(what, sizeof what, "value %zu is %.3g, beyond %g, which the rasterizer and the reference hold", i,
                     dst.out[i], SB_SCENE_MAX_COORD);
            return c.fail(where + "/output", what);
        }
    for (size_t i = 0; i < dst.in.size(); i++)
        if (fabs(dst.in[i]) > SB_SCENE_MAX_COORD)
        {
            char what[120];
            snprintf(what, sizeof what, "key time %zu is %.3g s, beyond %g s", i, dst.in[i], SB_SCENE_MAX_COORD);
            return c.fail(where + "/input", what);
        }
    size_t k = dst.in.size();
    bool cubic = smp.interpolation == "CUBICSPLINE";
    if (cubic && k > 0 && dst.out.size() == k * (size_t)ncomp) {   // the values without their tangents
        *skip = where + ": a CUBICSPLINE sampler has three values a key (in-tangent, value, out-tangent), this one "
                        "one (" + std::to_string(k) + " keys, " + std::to_string(k) + " values): left out";
        return true;
    }
    if (k > 0 && !(dst.in[0] >= 0)) {   // glTF 2.0: time[0] >= 0
        char what[160];
        snprintf(what, sizeof what, "/input: key 0 is at %.6g s, before 0 (glTF's key times start at 0 or later): "
                                    "left out", dst.in[0]);
        *skip = where + what;
        return true;
    }
    if (k == 0 || dst.out.size() != (cubic ? 3 : 1) * k * (size_t)ncomp) {
        *skip = where + ": the sampler's output count (" + std::to_string(dst.out.size() / (size_t)ncomp) +
                " values) does not match its input count (" + std::to_string(k) + " key times): left out";
        return true;
    }
    for (size_t i = 1; i < k; i++)
        if (!(dst.in[i] > dst.in[i - 1])) {
            *skip = where + "/input: key times do not increase (key " + std::to_string(i) + "): left out";
            return true;
        }
    for (size_t i = 0; ch.target_path == "rotation" && i < dst.out.size() / 4; i++) {   // values and tangents alike
        const double *q = &dst.out[4 * i];
        if (cubic && i % 3 != 1) continue;   // a tangent may be zero
        if (sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]) < 1e-6)
            return c.fail(where + "/output", "key " + std::to_string(cubic ? i / 3 : i) +
                                                 " is a zero-length quaternion, which is no rotation");
    }
    dst.s = {dst.in.data(), dst.out.data(), k, ncomp, ch.target_path == "rotation",
             cubic ? SB_INTERP_CUBIC : smp.interpolation == "STEP" ? SB_INTERP_STEP : SB_INTERP_LINEAR};
    return true;
}

// A primitive's vertex data, from accessors or a Draco bitstream.

// A primitive decoded once for every node that draws its mesh (when nothing
// per node changes it: no skin, no morph targets): its vertices, triangle
// list and whether it is closed (known after its first instance).
struct Decoded {
    PrimData d;
    std::vector<uint32_t> tris;
    int closed_known = 0;   // sb_prim_desc.closed_known
    uint32_t first_draw = 0;  // 1 + the draw its first placement became (0: none yet, or it cannot be shared)
    sb_m4 first_inv;          // that placement's world transform, inverted: later ones relative to it
    sb_m4 placed;             // and the transform itself
};

struct Loader {
    Ctx c;
    sb_scene *s;
    const sb_scene_opts *opts;
    ImageStore *images;
    std::vector<sb_m4> local, world;
    std::vector<int> parent;
    std::vector<std::vector<double>> weights;   // per node: morph weights (posed)
    std::vector<int> order;                     // nodes of the scene in visit order
    std::map<int, int32_t> tex_cache;           // glTF texture -> scene texture (-1: not decodable)
    std::map<std::pair<int, int>, std::shared_ptr<Decoded>> decoded = {};   // (mesh, primitive) -> decoded once
    std::vector<double> wp = {}, wn = {};       // emit's world positions and normals, reused
    std::vector<uint32_t> wt = {};              // and its triangles
    sb_motion *mo = nullptr;                    // the clips that play (NULL: none), handed to the scene
    std::vector<char> moves = {}, morphs = {};  // per node: a played clip moves it (or an ancestor); animates its weights

    bool fail(const std::string &where, const std::string &what) { return c.fail(where, what); }

    // A part of the file left out, not refused: said now, in info and in every run's warnings.
    void left_out(const std::string &why) {
        sb_log("%s: left out, not refused: %s", c.file, why.c_str());
        size_t l = strlen(s->unused);
        if (l + 3 < sizeof s->unused) snprintf(s->unused + l, sizeof s->unused - l, "%s%s", l ? "; " : "", why.c_str());
    }

    // Local transforms: the nodes' own, or sampled from the first animation at --pose T.
    bool pose() {
        const tinygltf::Model &m = *c.m;
        local.resize(m.nodes.size());
        weights.resize(m.nodes.size());
        std::vector<sb_trs> trs(m.nodes.size());
        for (size_t i = 0; i < m.nodes.size(); i++) {
            trs[i] = node_trs(m.nodes[i]);
            const tinygltf::Node &n = m.nodes[i];
            weights[i] = !n.weights.empty() ? n.weights : n.mesh >= 0 && n.mesh < (int)m.meshes.size() ? m.meshes[n.mesh].weights
                                                                                               : std::vector<double>();
        }
        std::vector<char> animated(m.nodes.size());
        if (opts->pose && !m.animations.empty()) {
            s->features.posed = true;
            const auto &an = m.animations[0];
            for (size_t ci = 0; ci < an.channels.size(); ci++) {
                const auto &ch = an.channels[ci];
                int ni = ch.target_node;
                if (ni < 0 || ni >= (int)m.nodes.size()) continue;
                std::string where = "/animations/0/channels/" + std::to_string(ci);
                bool w = ch.target_path == "weights";
                int ncomp = ch.target_path == "rotation" ? 4 : w ? (int)weights[ni].size() : 3;
                if (ncomp == 0) {
                    left_out(where + ": a weights channel on node " + std::to_string(ni) +
                             ", whose mesh has no morph weights: nothing for it to move: left out");
                    continue;
                }
                Channel chan;
                std::string skip;
                if (!read_channel(c, an, ch, where, ncomp, chan, &skip)) return false;
                if (!skip.empty()) {
                    left_out(skip);
                    continue;
                }
                double v[64] = {0};
                if (ncomp > 64) {   // as a clip that plays it: left out, said
                    left_out(where + ": " + std::to_string(ncomp) + " morph weights, more than the 64 played: not applied");
                    continue;
                }
                sb_anim_sample(&chan.s, opts->pose_time, v);
                double *dst = ch.target_path == "translation" ? trs[ni].t : ch.target_path == "rotation" ? trs[ni].r
                            : ch.target_path == "scale" ? trs[ni].s : nullptr;
                if (dst) memcpy(dst, v, sizeof(double) * ncomp), animated[ni] = 1;
                if (w) weights[ni].assign(v, v + ncomp);
            }
        }
        for (size_t i = 0; i < m.nodes.size(); i++)
            local[i] = animated[i] || m.nodes[i].matrix.size() != 16 ? sb_trs_matrix(&trs[i]) : node_local(m.nodes[i]);
        return true;
    }

    // World transforms of every node (joints may lie outside the scene), then
    // the scene's nodes depth-first without recursion (exported files hold
    // chains of tens of thousands of nodes), in a recursive walk's order.
    bool walk(const std::vector<int> &roots) {
        const tinygltf::Model &m = *c.m;
        world.assign(m.nodes.size(), sb_m4_identity());
        parent.assign(m.nodes.size(), -1);
        for (size_t i = 0; i < m.nodes.size(); i++)
            for (int ch : m.nodes[i].children)
                if (ch >= 0 && ch < (int)m.nodes.size()) parent[ch] = (int)i;
        std::vector<int> stack;
        for (size_t i = 0; i < m.nodes.size(); i++)
            if (parent[i] < 0) stack.push_back((int)i);
        while (!stack.empty()) { // the graph was checked to be a forest
            int ni = stack.back();
            stack.pop_back();
            world[ni] = parent[ni] < 0 ? local[ni] : sb_m4_mul(world[parent[ni]], local[ni]);
            if (!sb_m4_finite(world[ni])) return fail("/nodes/" + std::to_string(ni), "transform is not finite");
            for (int ch : m.nodes[ni].children) stack.push_back(ch);
        }
        std::vector<char> visited(m.nodes.size());
        for (size_t i = roots.size(); i-- > 0;) stack.push_back(roots[i]);
        while (!stack.empty()) {
            int ni = stack.back();
            stack.pop_back();
            std::string where = "/nodes/" + std::to_string(ni);
            if (ni < 0 || ni >= (int)m.nodes.size()) return fail(where, "node does not exist");
            if (visited[ni]) return fail(where, "node is reached twice (a cycle or a node with two parents)");
            visited[ni] = 1;
            order.push_back(ni);
            const std::vector<int> &ch = m.nodes[ni].children;
            for (size_t i = ch.size(); i-- > 0;) stack.push_back(ch[i]);
        }
        return true;
    }

    int32_t texture(int ti) {
        auto it = tex_cache.find(ti);
        if (it != tex_cache.end()) return it->second;
        int32_t r = decode_texture(ti);
        tex_cache[ti] = r;
        if (r < 0) s->features.undecodable_alpha++;
        else s->features.textures_decoded++;
        return r;
    }

    // An alpha texture that cannot be used: the first one's cause is said at load.
    int32_t cannot(const std::string &why) {
        if (images->first_cause.empty()) images->first_cause = why;
        return -1;
    }

    // The alpha of texture ti as a scene texture; -1 when its image cannot be read or decoded here.
    int32_t decode_texture(int ti) {
        const tinygltf::Model &m = *c.m;
        if (ti < 0 || ti >= (int)m.textures.size()) return -1;
        const tinygltf::Texture &t = m.textures[ti];
        auto bytes = images->bytes.find(t.source);
        std::string where = "/images/" + std::to_string(t.source);
        if (t.source < 0 || bytes == images->bytes.end()) {
            auto why = images->unread.find(t.source);
            return cannot(why != images->unread.end() ? why->second : where + ": no bytes (no uri, no bufferView)");
        }
        tinygltf::Image img;
        std::string e, w;
        if (!tinygltf::LoadImageData(&img, t.source, &e, &w, 0, 0, bytes->second.data(), (int)bytes->second.size(),
                                     nullptr) ||
            img.width <= 0 || img.height <= 0 || img.component <= 0)
            return cannot(where + ": its bytes do not decode as PNG, JPEG, BMP, TGA or GIF (another format, or a "
                                  "damaged file)");
        size_t n = (size_t)img.width * img.height, bpc = img.bits == 16 ? 2 : 1;
        if (img.image.size() < n * img.component * bpc) return -1;
        std::vector<uint8_t> alpha(n, 255);
        if (img.component == 2 || img.component == 4)
            for (size_t i = 0; i < n; i++) // the last channel; 16-bit: its high byte (little-endian)
                alpha[i] = img.image[(i * img.component + img.component - 1) * bpc + bpc - 1];
        uint32_t ws = 10497, wt = 10497;
        if (t.sampler >= 0 && t.sampler < (int)m.samplers.size()) {
            ws = (uint32_t)m.samplers[t.sampler].wrapS;
            wt = (uint32_t)m.samplers[t.sampler].wrapT;
        }
        return sb_scene_add_texture(s, (uint32_t)img.width, (uint32_t)img.height, alpha.data(), ws, wt);
    }

    // The alpha test of material mi (0: none) and the texture coordinate set it
    // reads; *drop for a BLEND material under --blend-casters none.
    uint32_t material(int mi, bool *drop, bool *double_sided, int *uv_set) {
        const tinygltf::Model &m = *c.m;
        *drop = false, *double_sided = false, *uv_set = 0;
        if (mi < 0 || mi >= (int)m.materials.size()) return 0;
        const tinygltf::Material &mat = m.materials[mi];
        *double_sided = mat.doubleSided;
        bool blend = mat.alphaMode == "BLEND", mask = mat.alphaMode == "MASK";
        if (blend) *drop = opts->blend == SB_BLEND_NONE;
        if (!mask && !(blend && opts->blend == SB_BLEND_MASK)) return 0;
        sb_material sm = {true, mask ? (float)mat.alphaCutoff : 0.5f, 1.0f, -1, {1, 0, 0, 0, 1, 0}};
        const auto &f = mat.pbrMetallicRoughness.baseColorFactor;
        if (f.size() == 4) sm.alpha = (float)f[3];
        const tinygltf::TextureInfo &bt = mat.pbrMetallicRoughness.baseColorTexture;
        if (bt.index >= 0) {
            sm.texture = texture(bt.index);
            *uv_set = bt.texCoord;
            auto tt = bt.extensions.find("KHR_texture_transform");
            if (tt != bt.extensions.end()) texture_transform(tt->second, sm.uv, uv_set);
        }
        return sb_scene_add_material(s, &sm);
    }

    // KHR_texture_transform as the spec's GLSL builds it: translation * rotation * scale.
    static void texture_transform(const tinygltf::Value &v, float uv[6], int *uv_set) {
        double o[2] = {0, 0}, sc[2] = {1, 1}, r = 0;
        auto num = [&](const char *key, int i, double def) {
            if (!v.Has(key)) return def;
            const tinygltf::Value &x = v.Get(key);
            const tinygltf::Value &e = x.IsArray() ? x.Get(i) : x;
            return e.IsNumber() ? e.GetNumberAsDouble() : def;
        };
        o[0] = num("offset", 0, 0), o[1] = num("offset", 1, 0);
        sc[0] = num("scale", 0, 1), sc[1] = num("scale", 1, 1);
        r = num("rotation", 0, 0);
        if (v.Has("texCoord") && v.Get("texCoord").IsInt()) *uv_set = v.Get("texCoord").GetNumberAsInt();
        double cs = cos(r), sn = sin(r);
        const double mtx[6] = {cs * sc[0], -sn * sc[1], o[0], sn * sc[0], cs * sc[1], o[1]};
        for (int k = 0; k < 6; k++) uv[k] = (float)mtx[k];
    }

    bool attribute(const tinygltf::Primitive &p, const std::string &where, const char *name, int ncomp,
                   std::vector<double> &out, bool *have) {
        auto it = p.attributes.find(name);
        *have = it != p.attributes.end();
        return !*have || read_vec(c, it->second, where + "/attributes/" + name, ncomp, out);
    }

    // Vertex data from the accessors.
    bool read_prim(const tinygltf::Primitive &p, const std::string &where, int uv_set, bool skinned, PrimData &d) {
        bool have;
        if (!attribute(p, where, "POSITION", 3, d.pos, &have)) return false;
        if (!have) return fail(where + "/attributes", "no POSITION");
        if (!attribute(p, where, "NORMAL", 3, d.nrm, &d.have_n)) return false;
        std::string uv = "TEXCOORD_" + std::to_string(uv_set);
        if (!attribute(p, where, uv.c_str(), 2, d.uv, &d.have_uv)) return false;
        for (int k = 0; skinned && k < 2; k++) {
            bool hj, hw;
            std::string j = "JOINTS_" + std::to_string(k), w = "WEIGHTS_" + std::to_string(k);
            if (!attribute(p, where, j.c_str(), 4, d.joints[k], &hj) || !attribute(p, where, w.c_str(), 4, d.weights[k], &hw))
                return false;
            if (hj != hw) return fail(where + "/attributes", j + " and " + w + " come in pairs");
            d.skin_sets += hj;
        }
        if (p.indices >= 0) return read_indices(c, p.indices, where + "/indices", d.idx);
        d.idx.resize(d.pos.size() / 3);
        for (size_t i = 0; i < d.idx.size(); i++) d.idx[i] = (uint32_t)i;
        return true;
    }

    // Vertex data from a KHR_draco_mesh_compression bitstream.
    bool read_draco(const tinygltf::Primitive &p, const tinygltf::Value &ext, const std::string &where, int uv_set,
                    bool skinned, PrimData &d) {
        std::string pd = where + "/extensions/KHR_draco_mesh_compression";
        const unsigned char *data;
        int view = ext.Get("bufferView").GetNumberAsInt();
        if (view < 0 || view >= (int)c.m->bufferViews.size()) return fail(pd + "/bufferView", "out of range");
        size_t len = c.m->bufferViews[view].byteLength;
        if (!view_range(c, view, 0, len, 1, 1, pd, &data)) return false;
        const tinygltf::Value &attrs = ext.Get("attributes");
        std::string uv = "TEXCOORD_" + std::to_string(uv_set);
        std::vector<std::string> names = {"POSITION", "NORMAL", uv};
        if (skinned) names.insert(names.end(), {"JOINTS_0", "WEIGHTS_0", "JOINTS_1", "WEIGHTS_1"});
        std::vector<std::string> present;
        int ids[SB_DRACO_MAX_ATTRS], nc[SB_DRACO_MAX_ATTRS], n = 0;
        for (const auto &name : names)
            if (attrs.Has(name) && p.attributes.count(name)) {
                present.push_back(name);
                ids[n] = attrs.Get(name).GetNumberAsInt();
                nc[n++] = name == "POSITION" || name == "NORMAL" ? 3 : name == uv ? 2 : 4;
            }
        if (present.empty() || present[0] != "POSITION") return fail(pd + "/attributes", "no POSITION");
        sb_draco_out out;
        char why[SB_ERR_LEN];
        if (!sb_draco_decode(data, len, ids, nc, n, &out, why, sizeof why)) return fail(pd, why);
        for (int a = 0; a < n; a++) {
            std::vector<double> v(out.values[a], out.values[a] + (size_t)nc[a] * out.points);
            const tinygltf::Accessor &acc = c.m->accessors[p.attributes.at(present[a])];
            if (acc.normalized && acc.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) // Draco keeps the raw integers
                for (double &x : v) x /= acc.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ? 255.0 : 65535.0;
            const std::string &name = present[a];
            if (name == "POSITION") d.pos = v;
            else if (name == "NORMAL") d.nrm = v, d.have_n = true;
            else if (name == uv) d.uv = v, d.have_uv = true;
            else (name[0] == 'J' ? d.joints : d.weights)[name.back() - '0'] = v;
        }
        d.skin_sets = !d.joints[0].empty() + !d.joints[1].empty();
        d.idx.assign(out.indices, out.indices + out.index_count);
        sb_draco_free(&out);
        s->features.draco++;
        return finite_all(c, pd, d.pos, 3);
    }

    // Morph targets at the node's weights.
    bool morph(const tinygltf::Primitive &p, const std::string &where, const std::vector<double> &w, PrimData &d) {
        for (size_t t = 0; t < p.targets.size() && t < w.size(); t++) {
            if (w[t] == 0) continue;
            for (const char *name : {"POSITION", "NORMAL"}) {
                auto it = p.targets[t].find(name);
                if (it == p.targets[t].end()) continue;
                std::vector<double> delta, &dst = name[0] == 'P' ? d.pos : d.nrm;
                std::string tp = where + "/targets/" + std::to_string(t) + "/" + name;
                if (!read_vec(c, it->second, tp, 3, delta)) return false;
                if (name[0] == 'N' && dst.empty()) continue;   // NORMAL deltas without normals: nothing to move
                if (delta.size() != dst.size())
                    return fail(tp, "count " + std::to_string(delta.size() / 3) + " differs from the primitive's " +
                                        std::to_string(dst.size() / 3) + " vertices");
                for (size_t i = 0; i < dst.size(); i++) dst[i] += w[t] * delta[i];
            }
        }
        return true;
    }

    // Skinned positions and normals: each vertex by its joints' world x inverse-bind matrices, weighted.
    bool skin(int si, const std::string &where, PrimData &d) {
        const tinygltf::Model &m = *c.m;
        const tinygltf::Skin &sk = m.skins[si];
        std::string sp = "/skins/" + std::to_string(si);
        std::vector<double> ibm;
        if (sk.inverseBindMatrices >= 0 && !read_vec(c, sk.inverseBindMatrices, sp + "/inverseBindMatrices", 16, ibm))
            return false;
        std::vector<sb_m4> jm(sk.joints.size());
        for (size_t j = 0; j < sk.joints.size(); j++) {
            int jn = sk.joints[j];
            if (jn < 0 || jn >= (int)m.nodes.size()) return fail(sp + "/joints/" + std::to_string(j), "node out of range");
            sb_m4 inv = sb_m4_identity();
            if (ibm.size() >= 16 * (j + 1))
                for (int k = 0; k < 16; k++) inv.m[k] = ibm[16 * j + k];
            if (det3(inv) == 0)   // it collapses every vertex the joint weighs onto a plane, a line or a point
                return fail(sp + "/inverseBindMatrices", "matrix " + std::to_string(j) +
                                                             " is not invertible (no bind pose maps to it)");
            jm[j] = sb_m4_mul(world[jn], inv);
        }
        size_t nv = d.pos.size() / 3;
        for (size_t v = 0; v < nv; v++) {
            double sum = 0;
            for (int set = 0; set < d.skin_sets; set++)
                for (int k = 0; k < 4; k++) {
                    double wv = d.weights[set][4 * v + k];
                    if (wv < 0) {   // glTF: never negative (a negative weight pushes the vertex away from its joint)
                        char num[32];
                        snprintf(num, sizeof num, "%g", wv);
                        return fail(where + "/attributes/WEIGHTS_" + std::to_string(set),
                                    "weight " + std::to_string(k) + " of vertex " + std::to_string(v) + " is " + num +
                                        " (glTF: joint weights are not negative)");
                    }
                    sum += wv;
                }
            if (!(fabs(sum) > 1e-6))   // glTF: a vertex's weights sum to 1; none at all would put it at the origin
                return fail(where + "/attributes/WEIGHTS_0", "the weights of vertex " + std::to_string(v) +
                                                                 " sum to 0 (glTF: to 1): it would collapse to the origin");
        }
        for (size_t v = 0; v < nv; v++)
            for (int set = 0; set < d.skin_sets; set++)
                for (int k = 0; k < 4; k++) {
                    size_t j = (size_t)d.joints[set][4 * v + k];
                    if (d.weights[set][4 * v + k] != 0 && j >= jm.size())
                        return fail(where + "/attributes/JOINTS_" + std::to_string(set),
                                    "joint " + std::to_string(j) + " of vertex " + std::to_string(v) +
                                        " is not in skin " + std::to_string(si));
                }
        if (mo && (size_t)si < mo->skin_ibm.size() && mo->skin_ibm[si].empty()) {   // what posing it again needs
            mo->skin_joints[si] = sk.joints;
            mo->skin_ibm[si].resize(jm.size());
            for (size_t j = 0; j < jm.size(); j++) {
                sb_m4 inv = sb_m4_identity();
                if (ibm.size() >= 16 * (j + 1))
                    for (int k = 0; k < 16; k++) inv.m[k] = ibm[16 * j + k];
                mo->skin_ibm[si][j] = inv;
            }
        }
        skin_vertices(jm, d, d.pos, d.nrm);
        return finite_all(c, where + " (skinned)", d.pos, 3);
    }

    // The morph targets' deltas of a primitive (each target's POSITION and NORMAL, empty where it has none).
    bool targets(const tinygltf::Primitive &p, const std::string &where, const PrimData &d, MoPlace &pl) {
        pl.dpos.resize(p.targets.size());
        pl.dnrm.resize(p.targets.size());
        for (size_t t = 0; t < p.targets.size(); t++)
            for (const char *name : {"POSITION", "NORMAL"}) {
                auto it = p.targets[t].find(name);
                if (it == p.targets[t].end()) continue;
                std::vector<double> &dst = name[0] == 'P' ? pl.dpos[t] : pl.dnrm[t];
                std::string tp = where + "/targets/" + std::to_string(t) + "/" + name;
                if (!read_vec(c, it->second, tp, 3, dst)) return false;
                const std::vector<double> &own = name[0] == 'P' ? d.pos : d.nrm;
                if (name[0] == 'N' && own.empty()) dst.clear();   // NORMAL deltas without normals: nothing to move
                else if (dst.size() != own.size())
                    return fail(tp, "count " + std::to_string(dst.size() / 3) + " differs from the primitive's " +
                                        std::to_string(own.size() / 3) + " vertices");
            }
        return true;
    }

    bool clips();
    bool clips_played(std::vector<char> &plays);
    bool clip_channels(sb_motion *mm, size_t ai, std::set<std::pair<int, int>> &claimed, std::vector<char> &animated);
    void clips_unplayed(const sb_motion *mm);

    bool prim(int node, int mesh, int pi, const std::vector<sb_m4> &instances);
    bool skin_moves(int si);
    bool triangles(const tinygltf::Primitive &p, const std::string &where, const PrimData &d, std::vector<uint32_t> &tris);
    bool emit(const PrimData &d, const std::vector<uint32_t> &tris, const sb_m4 *w, int node, uint32_t mat,
              bool double_sided, const float color[4], int *closed_known, Decoded *shared = nullptr);
    void reserve();
    bool instances(int ni, std::vector<sb_m4> &out);
    bool light(int ni);
    bool emit_nodes();
    bool anim_bound();
};

// The triangle list of a primitive (strips and fans unrolled), every index checked.
bool Loader::triangles(const tinygltf::Primitive &p, const std::string &where, const PrimData &d,
                       std::vector<uint32_t> &tris) {
    size_t nv = d.pos.size() / 3;
    const std::vector<uint32_t> &idx = d.idx;
    for (size_t i = 0; i < idx.size(); i++)
        if (idx[i] >= nv)
            return fail(where + "/indices", "index " + std::to_string(idx[i]) + " at " + std::to_string(i) +
                                                " is out of range (" + std::to_string(nv) + " vertices)");
    auto sized = [&](const std::vector<double> &v, int n, const char *name) {
        return v.empty() || v.size() == nv * n || fail(where + "/attributes/" + name, "count differs from POSITION");
    };
    if (!sized(d.nrm, 3, "NORMAL") || !sized(d.uv, 2, "TEXCOORD") || !sized(d.joints[0], 4, "JOINTS_0") ||
        !sized(d.weights[0], 4, "WEIGHTS_0") || !sized(d.joints[1], 4, "JOINTS_1") || !sized(d.weights[1], 4, "WEIGHTS_1"))
        return false;
    if (p.mode == 4 || p.mode < 0) {
        tris.assign(idx.begin(), idx.begin() + (idx.size() / 3) * 3);
    } else if (p.mode == 5) {
        for (size_t i = 2; i < idx.size(); i++) {
            if (i % 2 == 0) tris.insert(tris.end(), {idx[i - 2], idx[i - 1], idx[i]});
            else tris.insert(tris.end(), {idx[i - 1], idx[i - 2], idx[i]});
        }
    } else {
        for (size_t i = 2; i < idx.size(); i++) tris.insert(tris.end(), {idx[0], idx[i - 1], idx[i]});
    }
    return true;
}

// Adds the primitive to the scene in world space: under w (NULL: already there, skinned).
// closed_known: what is known of the primitive's closedness (0: nothing yet), updated after the first instance.
bool Loader::emit(const PrimData &d, const std::vector<uint32_t> &tris_in, const sb_m4 *w, int node, uint32_t mat,
                  bool double_sided, const float color[4], int *closed_known, Decoded *shared) {
    size_t nv = d.pos.size() / 3;
    const sb_m4 id = sb_m4_identity();
    const sb_m4 placed = w ? *w : id;
    if (w && !memcmp(w, &id, sizeof id)) w = nullptr;   // in place already: the vertices as they are, not a copy
    bool collapses = w && det3(*w) == 0;   // a zero scale can weld what was apart: work closedness out again
    const std::vector<uint32_t> *tris = &tris_in;
    const double *pos = d.pos.data(), *nrm = d.nrm.data();
    if (w) {
        if (det3(*w) < 0) { // a mirroring transform turns the winding: front faces stay front faces
            wt.assign(tris_in.begin(), tris_in.end());
            for (size_t i = 0; i < wt.size(); i += 3) std::swap(wt[i + 1], wt[i + 2]);
            tris = &wt;
        }
        wp.resize(d.pos.size());
        wn.resize(d.nrm.size());
        sb_m4 nm = normal_matrix(*w);
        for (size_t v = 0; v < nv; v++) {
            sb_v3 q = sb_m4_point(*w, sb_v3_make(d.pos[3 * v], d.pos[3 * v + 1], d.pos[3 * v + 2]));
            wp[3 * v] = q.x, wp[3 * v + 1] = q.y, wp[3 * v + 2] = q.z;
            if (!d.have_n) continue;
            sb_v3 n = sb_m4_dir(nm, sb_v3_make(d.nrm[3 * v], d.nrm[3 * v + 1], d.nrm[3 * v + 2]));
            wn[3 * v] = n.x, wn[3 * v + 1] = n.y, wn[3 * v + 2] = n.z;
        }
        pos = wp.data(), nrm = wn.data();
    }
    for (size_t i = 0; i < 3 * nv; i++)   // finite, and within what the rasterizer and the reference hold
        if (!(fabs(pos[i]) <= SB_SCENE_MAX_COORD)) {
            char what[200];
            snprintf(what, sizeof what, "vertex %zu of its mesh lies at %.3g as placed (the node's transform, skin and "
                     "morph weights applied), beyond %g, which the rasterizer and the reference hold", i / 3, pos[i],
                     SB_SCENE_MAX_COORD);
            return fail("/nodes/" + std::to_string(node), what);
        }
    sb_prim_desc pd;
    memset(&pd, 0, sizeof pd);
    pd.positions = pos;
    pd.normals = d.have_n ? nrm : nullptr;
    pd.uv = d.have_uv && mat ? d.uv.data() : nullptr;
    pd.vertex_count = (uint32_t)nv;
    pd.indices = tris->data();
    pd.index_count = (uint32_t)tris->size();
    memcpy(pd.color, color, sizeof pd.color);
    pd.double_sided = double_sided;
    pd.material = mat;
    pd.node = (uint32_t)node;
    pd.closed_known = collapses ? 0 : *closed_known;
    if (shared && shared->first_draw) {   // another placement of a primitive added before: relative to it
        sb_m4 rel = sb_m4_mul(placed, shared->first_inv);
        pd.instance_of = shared->first_draw;
        memcpy(pd.relative, rel.m, sizeof pd.relative);
    }
    sb_scene_add_prim(s, &pd);
    /* the first placement is the one later ones are placed from; a placement larger than it (left a copy of its
       own: sb_scene_add_prim shares none magnified) is from then on, so every shared placement is at most its
       proto's size */
    bool own = s->draws[s->draw_count - 1].proto == s->draw_count - 1;
    bool larger = shared && shared->first_draw && own && fabs(det3(placed)) > fabs(det3(shared->placed)) * (1 + 1e-9);
    if (shared && (!shared->first_draw || larger) && !collapses && sb_m4_invert(placed, &shared->first_inv)) {
        shared->first_draw = s->draw_count;
        shared->placed = placed;
    }
    if (!collapses && !*closed_known && !double_sided) *closed_known = s->draws[s->draw_count - 1].closed ? 2 : 1;
    return true;
}

// Room for every vertex, index and draw the scene's nodes will add (from the accessors' counts), so that the
// scene's arrays are not grown and copied as a large scene is flattened.
void Loader::reserve() {
    const tinygltf::Model &m = *c.m;
    uint64_t nv = 0, ni = 0;
    uint32_t nd = 0;
    auto count = [&](int a) -> uint64_t { return a >= 0 && a < (int)m.accessors.size() ? m.accessors[a].count : 0; };
    for (int ni_ : order) {
        const tinygltf::Node &n = m.nodes[ni_];
        if (n.mesh < 0 || n.mesh >= (int)m.meshes.size()) continue;
        uint64_t copies = 1;
        auto ext = n.extensions.find("EXT_mesh_gpu_instancing");
        if (ext != n.extensions.end() && ext->second.Has("attributes"))
            for (const char *name : {"TRANSLATION", "ROTATION", "SCALE"}) {
                const tinygltf::Value &a = ext->second.Get("attributes");
                if (a.Has(name) && a.Get(name).IsInt()) copies = std::max<uint64_t>(1, count(a.Get(name).GetNumberAsInt()));
            }
        for (const tinygltf::Primitive &p : m.meshes[n.mesh].primitives) {
            if (p.mode >= 0 && p.mode < 4) continue;
            auto pos = p.attributes.find("POSITION");
            uint64_t v = pos == p.attributes.end() ? 0 : count(pos->second), i = p.indices >= 0 ? count(p.indices) : v;
            if (p.mode == 5 || p.mode == 6) i = i >= 3 ? 3 * (i - 2) : 0;
            nv += v * copies;
            ni += i * copies;
            nd += (uint32_t)std::min<uint64_t>(copies, UINT32_MAX - nd);
        }
    }
    if (nv < (1ull << 32) && ni < (1ull << 32)) sb_scene_reserve(s, nv, ni, nd);
}

bool Loader::prim(int node, int mesh, int pi, const std::vector<sb_m4> &inst) {
    const tinygltf::Model &m = *c.m;
    const tinygltf::Primitive &p = m.meshes[mesh].primitives[pi];
    const tinygltf::Node &n = m.nodes[node];
    std::string where = "/meshes/" + std::to_string(mesh) + "/primitives/" + std::to_string(pi);
    if (p.mode > 6) return fail(where + "/mode", "unsupported primitive mode " + std::to_string(p.mode));
    if (p.mode >= 0 && p.mode < 4) return true; // points and lines neither cast nor receive shadows
    if (p.material >= (int)m.materials.size())
        return fail(where + "/material", "material " + std::to_string(p.material) + " does not exist");
    bool drop, ds;
    int uv_set;
    uint32_t mat = material(p.material, &drop, &ds, &uv_set);
    const tinygltf::Material *pm = p.material >= 0 ? &m.materials[p.material] : nullptr;
    if (pm && pm->alphaMode == "BLEND") s->features.blend++;
    if (pm && pm->alphaMode == "MASK") s->features.mask++;
    if (drop) return true;
    bool skinned = n.skin >= 0 && n.skin < (int)m.skins.size();
    // moves while the clips play: under an animated node, skinned by a moving joint, or morphed by animated weights
    bool moving = mo && (skinned ? skin_moves(n.skin) : moves[node]), morphing = mo && !p.targets.empty() && morphs[node];
    // decoded once for every node that shares the mesh, unless a skin or morph targets make it the node's own (or
    // it moves: its vertices are its own to pose)
    bool shared = !skinned && p.targets.empty() && !moving && !morphing;
    MoPlace place;
    std::shared_ptr<Decoded> dec;
    auto found = shared ? decoded.find({mesh, pi}) : decoded.end();
    if (found != decoded.end()) {
        dec = found->second;
    } else {
        dec = std::make_shared<Decoded>();
        auto dr = p.extensions.find("KHR_draco_mesh_compression");
        if (!(dr != p.extensions.end() ? read_draco(p, dr->second, where, uv_set, skinned, dec->d)
                                       : read_prim(p, where, uv_set, skinned, dec->d)) ||
            !triangles(p, where, dec->d, dec->tris))
            return false;
        if (moving || morphing) {   // the data before morph and skin, to pose again
            place.base = dec->d;
            if (morphing && !targets(p, where, dec->d, place)) return false;
        }
        if (!dec->tris.empty() && !p.targets.empty() && !morph(p, where, weights[node], dec->d)) return false;
        if (shared) decoded[{mesh, pi}] = dec;
    }
    PrimData &d = dec->d;
    const std::vector<uint32_t> &tris = dec->tris;
    if (tris.empty()) return true;
    if (mat && p.attributes.count("COLOR_0") && m.accessors[p.attributes.at("COLOR_0")].type == TINYGLTF_TYPE_VEC4)
        s->features.vertex_alpha_ignored++;
    skinned = skinned && d.skin_sets > 0;
    if (skinned && !skin(n.skin, where, d)) return false;
    float color[4] = {1, 1, 1, 1};
    if (pm)
        for (size_t k = 0; k < 4 && k < pm->pbrMetallicRoughness.baseColorFactor.size(); k++)
            color[k] = (float)pm->pbrMetallicRoughness.baseColorFactor[k];
    s->features.prims++;
    s->features.double_sided += ds;
    s->features.skinned += skinned;
    place.node = node;
    place.kind = skinned || morphing ? SB_DRAW_DEFORMING : SB_DRAW_RIGID;
    if (skinned) { // a skinned mesh ignores its node's transform (and instancing)
        int unknown = 0;
        place.first = s->vertex_count;
        if (!emit(d, tris, nullptr, node, mat, ds, color, &unknown)) return false;
        if (moving || morphing) {
            place.skin = n.skin;
            place.count = s->vertex_count - place.first;
            mo->places.push_back(std::move(place));
        }
        return true;
    }
    sb_m4 node_inv = sb_m4_identity();
    if ((moving || morphing) && !sb_m4_invert(world[node], &node_inv)) node_inv = sb_m4_identity();
    for (const sb_m4 &w : inst) {
        uint32_t first = s->vertex_count;
        if (!emit(d, tris, &w, node, mat, ds, color, &dec->closed_known, moving || morphing ? nullptr : dec.get()))
            return false;
        if (!(moving || morphing)) continue;
        mo->places.push_back(place);
        MoPlace &pl = mo->places.back();
        pl.first = first;
        pl.count = s->vertex_count - first;
        pl.inst = sb_m4_mul(node_inv, w);
    }
    return true;
}

// Whether a played clip moves one of the skin's joints.
bool Loader::skin_moves(int si) {
    for (int j : c.m->skins[si].joints)
        if (j >= 0 && j < (int)moves.size() && moves[j]) return true;
    return false;
}

// The clips that play (sb_scene_opts.anim): their channels read, the nodes they move marked. With every clip
// playing, a node's translation (rotation, scale, weights) is the first clip's that animates it: files hold
// clips meant one at a time (a character's walk and run), and the first is what a viewer shows.
static std::string clip_name(const tinygltf::Model &m, size_t ai) {
    return m.animations[ai].name.empty() ? std::to_string(ai) : m.animations[ai].name;
}

// Which clips play: all, or those --anim names (each a clip of the file, named once).
bool Loader::clips_played(std::vector<char> &plays) {
    const tinygltf::Model &m = *c.m;
    plays.assign(m.animations.size(), opts->anim == SB_ANIM_ALL);
    if (opts->anim != SB_ANIM_LIST) return true;
    std::string list = opts->anim_clips, all;
    for (size_t ai = 0; ai < m.animations.size(); ai++) all += (ai ? ", " : "") + clip_name(m, ai);
    for (size_t at = 0; at <= list.size();) {
        size_t comma = list.find(',', at);
        std::string name = list.substr(at, comma == std::string::npos ? std::string::npos : comma - at);
        at = comma == std::string::npos ? list.size() + 1 : comma + 1;
        size_t ai = 0;
        while (ai < m.animations.size() && clip_name(m, ai) != name) ai++;
        if (ai == m.animations.size())
            return fail("/animations", "--anim " + name + ": no clip of that name (its clips: " + all + ")");
        if (plays[ai]) return fail("/animations", "--anim " + list + ": clip " + name + " named twice");
        plays[ai] = 1;
    }
    return true;
}

// Clip ai's channels into mm: each (node, path) played by the first clip that claims it; what cannot be played
// as written is left out and said.
bool Loader::clip_channels(sb_motion *mm, size_t ai, std::set<std::pair<int, int>> &claimed,
                           std::vector<char> &animated) {
    const tinygltf::Model &m = *c.m;
    const size_t nn = m.nodes.size();
    const auto &an = m.animations[ai];
    MoClip clip;
    clip.name = clip_name(m, ai);
    std::set<int> nodes;
    for (size_t ci = 0; ci < an.channels.size(); ci++) {
        const auto &ch = an.channels[ci];
        int ni = ch.target_node, path = ch.target_path == "translation" ? PATH_T : ch.target_path == "rotation" ? PATH_R
                                       : ch.target_path == "scale" ? PATH_S : ch.target_path == "weights" ? PATH_W : -1;
        if (ni < 0 || ni >= (int)nn || path < 0) continue;   // a pointer channel: left out by the check, said
        int ncomp = path == PATH_R ? 4 : path == PATH_W ? (int)weights[ni].size() : 3;
        std::string where = "/animations/" + std::to_string(ai) + "/channels/" + std::to_string(ci), skip;
        if (ncomp > 64) {   // as --pose reads it: left out, said (never dropped in silence)
            left_out(where + ": " + std::to_string(ncomp) + " morph weights, more than the 64 played: not applied");
            mm->skipped++;
            continue;
        }
        if (ncomp == 0 && path == PATH_W) {   // never dropped in silence: the scene would say "nothing moves"
            left_out(where + ": a weights channel on node " + std::to_string(ni) +
                     ", whose mesh has no morph weights: nothing for it to move: left out");
            mm->skipped++;
            continue;
        }
        if (ncomp == 0 || !claimed.insert({ni, path}).second) continue;
        MoChannel mc{(int)mm->clips.size(), ni, path, {}};
        if (!read_channel(c, an, ch, where, ncomp, mc.ch, &skip)) return false;
        if (!skip.empty()) {
            left_out(skip);
            mm->skipped++;
            continue;
        }
        clip.duration = std::max(clip.duration, mc.ch.in.back());
        clip.channels++;
        nodes.insert(ni);
        animated[ni] = 1;
        (path == PATH_W ? morphs : moves)[ni] = 1;
        mm->channels.push_back(std::move(mc));
        mm->channels.back().ch.s.in = mm->channels.back().ch.in.data();   // the sampler reads its own arrays
        mm->channels.back().ch.s.out = mm->channels.back().ch.out.data();
    }
    clip.nodes = (uint32_t)nodes.size();
    mm->clips.push_back(clip);
    return true;
}

// What the clips would move that the tool does not play: said, never silent (a moved light, a mirroring scale key).
void Loader::clips_unplayed(const sb_motion *mm) {
    const tinygltf::Model &m = *c.m;
    for (size_t ni = 0; ni < m.nodes.size(); ni++)
        if (moves[ni] && m.nodes[ni].extensions.count("KHR_lights_punctual"))
            left_out("/nodes/" + std::to_string(ni) + ": its light is moved by a clip; lights stay where the file "
                     "places them (the shadows and the reference are of that place)");
    for (const MoChannel &mc : mm->channels) {
        if (mc.path != PATH_S) continue;
        const sb_trs &r = mm->rest[mc.node];
        bool rest_mirrors = r.s[0] * r.s[1] * r.s[2] < 0;
        size_t keys = mc.ch.in.size(), nc = keys ? mc.ch.out.size() / keys : 0;
        size_t at = mc.ch.s.interp == SB_INTERP_CUBIC ? 3 : 0;   // a cubic key's value follows its in-tangent
        for (size_t k = 0; k < keys; k++) {
            const double *v = &mc.ch.out[k * nc + at];
            if ((v[0] * v[1] * v[2] < 0) != rest_mirrors) {
                left_out("/nodes/" + std::to_string(mc.node) + ": a scale key (" + std::to_string(k) + ") mirrors it "
                         "where its rest pose does not, or the other way: its triangles keep their rest pose's "
                         "winding, so on those frames their other side faces out (single-sided: culled)");
                break;
            }
        }
    }
}

bool Loader::clips() {
    const tinygltf::Model &m = *c.m;
    size_t nn = m.nodes.size();
    moves.assign(nn, 0);
    morphs.assign(nn, 0);
    if (opts->anim == SB_ANIM_LIST && m.animations.empty())
        return fail("/animations", std::string("--anim ") + opts->anim_clips + ": the file has no animation clip");
    if (opts->pose || opts->anim == SB_ANIM_NONE || m.animations.empty()) return true;
    std::vector<char> plays;
    if (!clips_played(plays)) return false;
    std::unique_ptr<sb_motion> mm(new sb_motion);
    mm->parent = parent;
    mm->rest.resize(nn);
    mm->has_matrix.resize(nn);
    mm->rest_local.resize(nn);
    mm->rest_weights = weights;
    for (size_t i = 0; i < nn; i++) {
        mm->rest[i] = node_trs(m.nodes[i]);
        mm->has_matrix[i] = m.nodes[i].matrix.size() == 16;
        mm->rest_local[i] = node_local(m.nodes[i]);
    }
    std::vector<std::vector<int>> children(nn);   // parents first: roots, then breadth-first
    for (size_t i = 0; i < nn; i++)
        if (parent[i] >= 0) children[parent[i]].push_back((int)i);
        else mm->topo.push_back((int)i);
    for (size_t k = 0; k < mm->topo.size(); k++)
        for (int ch : children[mm->topo[k]]) mm->topo.push_back(ch);
    std::set<std::pair<int, int>> claimed;
    std::vector<char> animated(nn);
    for (size_t ai = 0; ai < m.animations.size(); ai++)
        if (plays[ai] && !clip_channels(mm.get(), ai, claimed, animated)) return false;
    for (int ni : mm->topo)   // a node under a moving one moves
        if (parent[ni] >= 0 && moves[parent[ni]]) moves[ni] = 1;
    clips_unplayed(mm.get());
    for (char a : animated) mm->animated_nodes += a;
    mm->skin_joints.resize(m.skins.size());
    mm->skin_ibm.resize(m.skins.size());
    if (!mm->channels.empty()) mo = mm.release();
    else if (mm->skipped) sb_log("%s: no clip channel can be played: the scene stands still", c.file);
    return true;
}

// The node's world transform, or one for each EXT_mesh_gpu_instancing instance.
bool Loader::instances(int ni, std::vector<sb_m4> &out) {
    const tinygltf::Node &n = c.m->nodes[ni];
    out.assign(1, world[ni]);
    auto ext = n.extensions.find("EXT_mesh_gpu_instancing");
    if (ext == n.extensions.end() || !ext->second.Has("attributes")) return true;
    const tinygltf::Value &a = ext->second.Get("attributes");
    std::string where = "/nodes/" + std::to_string(ni) + "/extensions/EXT_mesh_gpu_instancing/attributes/";
    std::vector<double> v[3];
    const char *names[3] = {"TRANSLATION", "ROTATION", "SCALE"};
    size_t count = SIZE_MAX;
    for (int k = 0; k < 3; k++) {
        if (!a.Has(names[k]) || !a.Get(names[k]).IsInt()) continue;
        if (!read_vec(c, a.Get(names[k]).GetNumberAsInt(), where + names[k], k == 1 ? 4 : 3, v[k])) return false;
        size_t cnt = v[k].size() / (k == 1 ? 4 : 3);
        if (count != SIZE_MAX && cnt != count) return fail(where + names[k], "count differs from the other attributes");
        count = cnt;
    }
    if (count == SIZE_MAX) return true;
    out.resize(count);
    for (size_t i = 0; i < count; i++) {
        sb_trs x = {{0, 0, 0}, {0, 0, 0, 1}, {1, 1, 1}};
        for (int k = 0; k < 3 && !v[0].empty(); k++) x.t[k] = v[0][3 * i + k];
        for (int k = 0; k < 4 && !v[1].empty(); k++) x.r[k] = v[1][4 * i + k];
        for (int k = 0; k < 3 && !v[2].empty(); k++) x.s[k] = v[2][3 * i + k];
        out[i] = sb_m4_mul(world[ni], sb_trs_matrix(&x));
    }
    s->features.instanced_nodes++;
    s->features.instances += (uint32_t)count;
    return true;
}

bool Loader::light(int ni) {
    const tinygltf::Model &m = *c.m;
    const tinygltf::Node &n = m.nodes[ni];
    auto ext = n.extensions.find("KHR_lights_punctual");
    if (ext == n.extensions.end() || !ext->second.Has("light")) return true;
    int li = ext->second.Get("light").GetNumberAsInt();
    if (li < 0 || li >= (int)m.lights.size())
        return fail("/nodes/" + std::to_string(ni) + "/extensions/KHR_lights_punctual/light",
                    "light " + std::to_string(li) + " does not exist");
    const tinygltf::Light &L = m.lights[li];
    sb_light l;
    memset(&l, 0, sizeof l);
    l.type = L.type == "directional" ? SB_LIGHT_DIRECTIONAL : L.type == "spot" ? SB_LIGHT_SPOT : SB_LIGHT_POINT;
    l.position = sb_m4_point(world[ni], sb_v3_make(0, 0, 0));
    if (!(fabs(l.position.x) <= SB_SCENE_MAX_COORD && fabs(l.position.y) <= SB_SCENE_MAX_COORD &&
          fabs(l.position.z) <= SB_SCENE_MAX_COORD))
        return fail("/nodes/" + std::to_string(ni), "its light stands beyond 1e12 from the origin, which the "
                                                    "rasterizer and the reference hold");
    sb_v3 dir = sb_m4_dir(world[ni], sb_v3_make(0, 0, -1));
    if (l.type != SB_LIGHT_POINT && !(sb_v3_len(dir) > 1e-12)) {   /* a sun or spot that points nowhere lights nothing */
        left_out("/nodes/" + std::to_string(ni) + ": its " + (l.type == SB_LIGHT_SPOT ? "spot" : "directional") +
                 " light " + std::to_string(li) + " has no direction (the node's world transform scales its -Z to 0)");
        return true;
    }
    l.direction = sb_v3_norm(dir);
    for (int k = 0; k < 3; k++) l.color[k] = k < (int)L.color.size() ? (float)L.color[k] : 1.0f;
    l.intensity = L.intensity;
    l.range = L.range;
    l.cone = l.type == SB_LIGHT_SPOT ? L.spot.outerConeAngle : 0;
    s->lights = (sb_light *)sb_xrealloc(s->lights, (s->light_count + 1) * sizeof(sb_light));
    s->lights[s->light_count++] = l;
    if (l.type == SB_LIGHT_DIRECTIONAL && !s->has_sun) {
        s->has_sun = true;
        s->sun = sb_v3_scale(l.direction, -1);
    }
    return true;
}

// The farthest any vertex of a moving placement can lie from the origin under every pose its clips can take,
// bounded from the keys (never by playing them): a node maps |x| to at most s|x| + t, where s is the largest
// scale its rest transform or a key gives (rotations keep lengths) and t the farthest translation, a cubic key
// widened by its tangents' reach; down the hierarchy the bounds compose, a morphing mesh adds each target's
// farthest delta times its weight's largest key, a skinned one takes its farthest joint times its weights' sum.
// Past SB_SCENE_MAX_COORD the file is refused at load, naming the node (the rasterizer and the reference would
// otherwise be handed what they cannot hold mid-run).
bool Loader::anim_bound() {
    if (!mo || mo->places.empty()) return true;
    size_t nn = mo->parent.size();
    auto norm3 = [](const double *v) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); };
    auto mat_scale = [](const sb_m4 &m) {   // how far the upper 3x3 A stretches at most: sqrt of the largest row
        double most = 0;                     // sum of |A^T A| (Gershgorin): exact for a rotation and scale
        for (int i = 0; i < 3; i++) {
            double row = 0;
            for (int j = 0; j < 3; j++) {
                double ata = 0;
                for (int r = 0; r < 3; r++) ata += m.m[i * 4 + r] * m.m[j * 4 + r];
                row += fabs(ata);
            }
            most = std::max(most, row);
        }
        return sqrt(most);
    };
    std::vector<double> sc(nn), tr(nn);
    std::vector<std::vector<double>> wmax(nn);
    for (size_t i = 0; i < nn; i++) {
        const sb_trs &x = mo->rest[i];   // a TRS node stretches by its largest scale (its rotation keeps lengths)
        sc[i] = mo->has_matrix[i] ? mat_scale(mo->rest_local[i])
                                  : std::max({fabs(x.s[0]), fabs(x.s[1]), fabs(x.s[2])});
        tr[i] = norm3(&mo->rest_local[i].m[12]);
        wmax[i] = mo->rest_weights[i];
        for (double &w : wmax[i]) w = fabs(w);
    }
    for (const MoChannel &mc : mo->channels) {
        const Channel &ch = mc.ch;
        size_t keys = ch.in.size(), nc = keys ? ch.out.size() / keys : 0;   // values a key (x3 with tangents)
        bool cubic = ch.s.interp == SB_INTERP_CUBIC;
        int ncomp = cubic ? (int)nc / 3 : (int)nc;
        double dt = 0;
        for (size_t k = 1; k < keys; k++) dt = std::max(dt, ch.in[k] - ch.in[k - 1]);
        for (size_t k = 0; k < keys; k++)
            for (int part = 0; part < (cubic ? 3 : 1); part++) {
                const double *v = &ch.out[k * nc + (size_t)part * ncomp];
                double reach = !cubic || part == 1 ? 1 : 0.15 * dt;   // Hermite: a tangent moves at most 4/27 dt
                if (mc.path == PATH_T) tr[mc.node] = std::max(tr[mc.node], reach * norm3(v));
                if (mc.path == PATH_S)
                    sc[mc.node] = std::max(sc[mc.node], reach * std::max({fabs(v[0]), fabs(v[1]), fabs(v[2])}));
                for (int w = 0; mc.path == PATH_W && w < ncomp && (size_t)w < wmax[mc.node].size(); w++)
                    wmax[mc.node][w] = std::max(wmax[mc.node][w], reach * fabs(v[w]));
            }
    }
    std::vector<double> sw(nn, 1), tw(nn, 0);
    for (int ni : mo->topo) {
        int p = mo->parent[ni];
        sw[ni] = (p < 0 ? 1 : sw[p]) * sc[ni];
        tw[ni] = (p < 0 ? 0 : tw[p]) + (p < 0 ? 1 : sw[p]) * tr[ni];
    }
    for (const MoPlace &pl : mo->places) {
        const sbm::RestData &b = pl.base;
        double r = 0, wsum = 0;
        for (size_t v = 0; v < b.pos.size() / 3; v++) r = std::max(r, norm3(&b.pos[3 * v]));
        for (size_t t = 0; t < pl.dpos.size(); t++) {   // morph targets at their weights' largest keys
            double far = 0;
            for (size_t v = 0; v < pl.dpos[t].size() / 3; v++) far = std::max(far, norm3(&pl.dpos[t][3 * v]));
            r += far * (pl.node >= 0 && t < wmax[pl.node].size() ? wmax[pl.node][t] : 0);
        }
        double bound;
        if (pl.skin >= 0) {
            for (size_t v = 0; v < b.pos.size() / 3; v++) {
                double sum = 0;
                for (int set = 0; set < b.skin_sets; set++)
                    for (int k = 0; k < 4; k++) sum += fabs(b.weights[set][4 * v + k]);
                wsum = std::max(wsum, sum);
            }
            double joint = 0;
            const std::vector<int> &joints = mo->skin_joints[pl.skin];
            for (size_t j = 0; j < joints.size(); j++) {
                const sb_m4 &ibm = mo->skin_ibm[pl.skin][j];
                joint = std::max(joint, sw[joints[j]] * (mat_scale(ibm) * r + norm3(&ibm.m[12])) + tw[joints[j]]);
            }
            bound = wsum * joint;
        } else {
            bound = sw[pl.node] * (mat_scale(pl.inst) * r + norm3(&pl.inst.m[12])) + tw[pl.node];
        }
        if (!(bound <= SB_SCENE_MAX_COORD)) {
            char what[300];
            snprintf(what, sizeof what, "as its clips can pose it (their keys' largest translations, scales and "
                     "weights), a vertex of its mesh may lie %.3g from the origin, beyond %g, which the rasterizer and "
                     "the reference hold", bound, SB_SCENE_MAX_COORD);
            return fail("/nodes/" + std::to_string(pl.node), what);
        }
    }
    return true;
}

// Every node of the scene in visit order: its primitives, camera and light.
bool Loader::emit_nodes() {
    const tinygltf::Model &m = *c.m;
    std::set<int> skins;
    for (int ni : order) {
        const tinygltf::Node &n = m.nodes[ni];
        std::string where = "/nodes/" + std::to_string(ni);
        if (n.mesh >= 0) {
            if (n.mesh >= (int)m.meshes.size()) return fail(where + "/mesh", "mesh " + std::to_string(n.mesh) + " does not exist");
            s->nodes_drawn++;
            std::vector<sb_m4> inst;
            if (!instances(ni, inst)) return false;
            if (n.skin >= 0) skins.insert(n.skin);
            for (size_t pi = 0; pi < m.meshes[n.mesh].primitives.size(); pi++)
                if (!prim(ni, n.mesh, (int)pi, inst)) return false;
        }
        if (n.camera >= 0 && n.camera < (int)s->camera_count) s->cameras[n.camera].node = ni;
        if (!light(ni)) return false;
    }
    s->features.skins = (uint32_t)skins.size();
    return true;
}

// ---- the document into tinygltf's model ----
//
// The file is parsed once, by the project's exact JSON reader, and held to the
// specification as parsed (gltf_check.h); tinygltf's model is then filled from
// that same document: tinygltf 2.7 takes only text (it would parse it a second
// time) and coerces numbers on the way (a negative offset read as 0, an index
// above 2^31 truncated), which the checks had already refused. Every value
// read here has passed them, so this reads without re-checking ranges.

// Buffers and images are read from here: data: URIs, the .glb's BIN chunk, or
// files inside the scene's folder (unless allowed), each file hashed for the
// scene cache and the content hash.
struct Source {
    std::string base_dir;
    bool allow_external;
    const unsigned char *bin;
    uint64_t bin_len;
    uint64_t hash;   // of the file, then of every file read (buffers, images), in order
};

const sb_json *member(const sb_json *o, const char *key) { return o ? sb_json_get(o, key) : nullptr; }
// Every integer glTF field read here is an index or an enum: a number that is no int (1e30, 2.5) reads as
// INT_MAX, an index nothing has and a value no enum holds, so the checks that follow refuse it by name.
int int_of(const sb_json *o, const char *key, int def) {
    const sb_json *v = member(o, key);
    if (!v || v->type != SB_JSON_NUMBER) return def;
    return v->num >= INT_MIN && v->num <= INT_MAX && v->num == (int)v->num ? (int)v->num : INT_MAX;
}
size_t size_of(const sb_json *o, const char *key) {
    uint64_t u = 0;
    const sb_json *v = member(o, key);
    return v && sb_json_u64(v, &u) ? (size_t)u : 0;
}
double num_of(const sb_json *o, const char *key, double def) {
    const sb_json *v = member(o, key);
    return v && v->type == SB_JSON_NUMBER ? v->num : def;
}
bool bool_of(const sb_json *o, const char *key, bool def) {
    const sb_json *v = member(o, key);
    return v && v->type == SB_JSON_BOOL ? v->b : def;
}
std::string str_of(const sb_json *o, const char *key, const char *def) {
    const sb_json *v = member(o, key);
    return v && v->type == SB_JSON_STRING ? v->text : def;
}
std::vector<double> nums_of(const sb_json *o, const char *key) {
    std::vector<double> r;
    const sb_json *v = member(o, key);
    for (uint32_t i = 0; v && v->type == SB_JSON_ARRAY && i < v->count; i++) r.push_back(v->items[i].num);
    return r;
}
std::vector<int> ints_of(const sb_json *o, const char *key) {
    std::vector<int> r;
    const sb_json *v = member(o, key);
    for (uint32_t i = 0; v && v->type == SB_JSON_ARRAY && i < v->count; i++) r.push_back((int)v->items[i].num);
    return r;
}
// Each item of an array member (nothing when absent).
template <typename F> void each(const sb_json *o, const char *key, F f) {
    const sb_json *v = member(o, key);
    for (uint32_t i = 0; v && v->type == SB_JSON_ARRAY && i < v->count; i++) f(&v->items[i]);
}

tinygltf::Value value_of(const sb_json *v) {
    switch (v->type) {
    case SB_JSON_BOOL: return tinygltf::Value(v->b);
    case SB_JSON_NUMBER:
        if (v->num == std::floor(v->num) && std::fabs(v->num) < 2147483648.0 && !strpbrk(v->text, ".eE"))
            return tinygltf::Value((int)v->num);
        return tinygltf::Value(v->num);
    case SB_JSON_STRING: return tinygltf::Value(std::string(v->text));
    case SB_JSON_ARRAY: {
        tinygltf::Value::Array a;
        for (uint32_t i = 0; i < v->count; i++) a.push_back(value_of(&v->items[i]));
        return tinygltf::Value(std::move(a));
    }
    case SB_JSON_OBJECT: {
        tinygltf::Value::Object o;
        for (uint32_t i = 0; i < v->count; i++) o.emplace(v->items[i].key, value_of(&v->items[i]));   // the first wins
        return tinygltf::Value(std::move(o));
    }
    default: return tinygltf::Value();
    }
}
tinygltf::ExtensionMap extensions_of(const sb_json *o) {
    tinygltf::ExtensionMap m;
    const sb_json *e = member(o, "extensions");
    for (uint32_t i = 0; e && e->type == SB_JSON_OBJECT && i < e->count; i++) m.emplace(e->items[i].key, value_of(&e->items[i]));
    return m;
}

bool base64_decode(const char *s, std::vector<unsigned char> &out) {
    uint32_t acc = 0;
    int bits = 0;
    for (; *s && *s != '='; s++) {
        const char *p = strchr("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/", *s);
        if (!p || !*s) return false;
        acc = acc << 6 | (uint32_t)(p - "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/");
        if ((bits += 6) >= 8) out.push_back((unsigned char)(acc >> (bits -= 8)));
    }
    return true;
}

// The bytes a buffer's or image's uri names (a data: URI, or a file checked by sb_uri_resolve).
bool read_uri(Source &src, const char *file, const std::string &where, const char *uri, std::vector<unsigned char> &out,
              sb_err *err) {
    if (!strncmp(uri, "data:", 5)) {
        const char *comma = strchr(uri, ',');
        if (!comma || !strstr(std::string(uri, comma).c_str(), ";base64") || !base64_decode(comma + 1, out))
            return sb_fail(err, "%s: %s/uri: a data: URI that is not base64", file, where.c_str());
        return true;
    }
    char real[PATH_MAX];
    sb_err e;
    if (!sb_uri_resolve(src.base_dir.c_str(), uri, src.allow_external, real, sizeof real, &e))
        return sb_fail(err, "%s: %s/uri: %s", file, where.c_str(), e.msg);
    size_t n = 0;
    char *data = sb_read_file(real, &n, &e);
    if (!data) return sb_fail(err, "%s: %s/uri: %s", file, where.c_str(), e.msg);
    uint64_t h = sb_hash_bytes(SB_FNV_SEED, data, n);
    src.hash = sb_fnv1a(src.hash, &h, sizeof h);
    sb_scene_cache_note_file(real, h);
    out.assign(data, data + n);
    free(data);
    return true;
}

bool read_buffers(const sb_json *root, Source &src, const char *file, Document &doc, sb_err *err) {
    const sb_json *bs = member(root, "buffers");
    doc.owned.resize(bs ? bs->count : 0);
    uint8_t *used_bits = sb_gltf_used_buffers(root);
    std::vector<uint8_t> used(bs ? bs->count : 0, 0);
    if (used_bits) std::copy(used_bits, used_bits + used.size(), used.begin());
    free(used_bits);
    for (uint32_t i = 0; bs && i < bs->count; i++) {
        const sb_json *b = &bs->items[i];
        std::string where = "/buffers/" + std::to_string(i);
        size_t len = size_of(b, "byteLength");
        const sb_json *uri = member(b, "uri");
        std::vector<unsigned char> &own = doc.owned[i];
        if (!used[i]) {
            doc.bufs.emplace_back(nullptr, 0);   // nothing reads it: never opened
        } else if (uri) {
            if (!read_uri(src, file, where, uri->text, own, err)) return false;
            if (own.size() < len)
                return sb_fail(err, "%s: %s/byteLength: %zu bytes, but its uri (%.200s) holds %zu: cut short?", file,
                               where.c_str(), len, strncmp(uri->text, "data:", 5) ? uri->text : "a data: URI",
                               own.size());
            doc.bufs.emplace_back(own.data(), len);
        } else if (i == 0 && src.bin) {
            doc.bufs.emplace_back(src.bin, len);   // the .glb's BIN chunk, where it is (the check saw that it fits)
        } else {
            doc.bufs.emplace_back(nullptr, 0);   // no bytes, and nothing reads it (the check saw to that)
        }
    }
    return true;
}

// The images an alpha test reads: the base-colour texture's of every MASK material, and of every BLEND material
// alpha-tested under --blend-casters mask. No other image is ever opened.
std::vector<bool> alpha_images(const tinygltf::Model &m, const sb_scene_opts *opts) {
    std::vector<bool> need(m.images.size(), false);
    for (const tinygltf::Material &mat : m.materials) {
        bool tested = mat.alphaMode == "MASK" || (mat.alphaMode == "BLEND" && opts->blend == SB_BLEND_MASK);
        int ti = mat.pbrMetallicRoughness.baseColorTexture.index;
        if (!tested || ti < 0 || ti >= (int)m.textures.size()) continue;
        int src = m.textures[ti].source;
        if (src >= 0 && src < (int)need.size()) need[src] = true;
    }
    return need;
}

// The encoded bytes of every image an alpha test reads (decoded later). One that cannot be read is kept with its
// reason, as one that cannot be decoded is: the load goes on, and says why (log_features).
bool read_images(const sb_json *root, Source &src, const char *file, const tinygltf::Model &m, const Document &doc,
                 const sb_scene_opts *opts, ImageStore *images) {
    const sb_json *is = member(root, "images");
    std::vector<bool> need = alpha_images(m, opts);
    for (uint32_t i = 0; is && i < is->count; i++) {
        if (i >= need.size() || !need[i]) continue;
        const sb_json *img = &is->items[i];
        std::string where = "/images/" + std::to_string(i);
        std::vector<unsigned char> bytes;
        const sb_json *uri = member(img, "uri");
        if (uri) {
            sb_err e;
            if (!read_uri(src, file, where, uri->text, bytes, &e)) {
                const char *why = strstr(e.msg, "/uri: ");
                images->unread[(int)i] = where + " (" + std::string(uri->text).substr(0, 200) + "): " +
                                         (why ? why + 6 : e.msg);
                continue;
            }
        } else {
            int v = int_of(img, "bufferView", -1);
            if (v < 0 || v >= (int)m.bufferViews.size()) continue;
            const tinygltf::BufferView &bv = m.bufferViews[v];
            const unsigned char *data = doc.bufs[bv.buffer].first;
            if (data) bytes.assign(data + bv.byteOffset, data + bv.byteOffset + bv.byteLength);
        }
        if (!bytes.empty()) images->bytes[(int)i] = std::move(bytes);
    }
    return true;
}

int accessor_type(const std::string &t) {
    static const std::pair<const char *, int> types[] = {
        {"SCALAR", TINYGLTF_TYPE_SCALAR}, {"VEC2", TINYGLTF_TYPE_VEC2}, {"VEC3", TINYGLTF_TYPE_VEC3},
        {"VEC4", TINYGLTF_TYPE_VEC4},     {"MAT2", TINYGLTF_TYPE_MAT2}, {"MAT3", TINYGLTF_TYPE_MAT3},
        {"MAT4", TINYGLTF_TYPE_MAT4}};
    for (const auto &x : types)
        if (t == x.first) return x.second;
    return -1;
}

std::map<std::string, int> attributes_of(const sb_json *o) {
    std::map<std::string, int> m;
    for (uint32_t i = 0; o && o->type == SB_JSON_OBJECT && i < o->count; i++) m.emplace(o->items[i].key, (int)o->items[i].num);
    return m;
}

// The checked document into tinygltf's model (buffers and images read as it goes).
// The buffer views and accessors (a sparse accessor's fields as tinygltf's ints); false: said.
static bool model_accessors(const sb_json *root, const char *file, tinygltf::Model &m, sb_err *err) {
    each(root, "bufferViews", [&](const sb_json *o) {
        tinygltf::BufferView v;
        v.buffer = int_of(o, "buffer", -1);
        v.byteOffset = size_of(o, "byteOffset");
        v.byteLength = size_of(o, "byteLength");
        v.byteStride = size_of(o, "byteStride");
        m.bufferViews.push_back(v);
    });
    bool ok = true;
    each(root, "accessors", [&](const sb_json *o) {
        tinygltf::Accessor a;
        a.bufferView = int_of(o, "bufferView", -1);
        a.byteOffset = size_of(o, "byteOffset");
        a.normalized = bool_of(o, "normalized", false);
        a.componentType = int_of(o, "componentType", -1);
        a.count = size_of(o, "count");
        a.type = accessor_type(str_of(o, "type", ""));
        a.minValues = nums_of(o, "min");
        a.maxValues = nums_of(o, "max");
        const sb_json *sp = member(o, "sparse");
        a.sparse.isSparse = sp != nullptr;
        if (sp) {
            const sb_json *in = member(sp, "indices"), *va = member(sp, "values");
            size_t count = size_of(sp, "count"), io = size_of(in, "byteOffset"), vo = size_of(va, "byteOffset");
            if (count > INT_MAX || io > INT_MAX || vo > INT_MAX) ok = false;   // tinygltf's sparse fields are int
            a.sparse.count = (int)count;
            a.sparse.indices.bufferView = int_of(in, "bufferView", -1);
            a.sparse.indices.byteOffset = (int)io;
            a.sparse.indices.componentType = int_of(in, "componentType", -1);
            a.sparse.values.bufferView = int_of(va, "bufferView", -1);
            a.sparse.values.byteOffset = (int)vo;
        }
        m.accessors.push_back(a);
    });
    return ok || sb_fail(err, "%s: a sparse accessor's count or offset is beyond 2^31 - 1, which is not supported", file);
}

// The meshes and their primitives, the nodes, the skins.
static void model_meshes(const sb_json *root, tinygltf::Model &m) {
    each(root, "meshes", [&](const sb_json *o) {
        tinygltf::Mesh mesh;
        each(o, "primitives", [&](const sb_json *q) {
            tinygltf::Primitive p;
            p.attributes = attributes_of(member(q, "attributes"));
            p.indices = int_of(q, "indices", -1);
            p.material = int_of(q, "material", -1);
            p.mode = int_of(q, "mode", TINYGLTF_MODE_TRIANGLES);
            each(q, "targets", [&](const sb_json *t) { p.targets.push_back(attributes_of(t)); });
            p.extensions = extensions_of(q);
            mesh.primitives.push_back(std::move(p));
        });
        mesh.weights = nums_of(o, "weights");
        m.meshes.push_back(std::move(mesh));
    });
    each(root, "nodes", [&](const sb_json *o) {
        tinygltf::Node n;
        n.mesh = int_of(o, "mesh", -1);
        n.skin = int_of(o, "skin", -1);
        n.camera = int_of(o, "camera", -1);
        n.children = ints_of(o, "children");
        n.matrix = nums_of(o, "matrix");
        n.translation = nums_of(o, "translation");
        n.rotation = nums_of(o, "rotation");
        n.scale = nums_of(o, "scale");
        n.weights = nums_of(o, "weights");
        n.extensions = extensions_of(o);
        m.nodes.push_back(std::move(n));
    });
    each(root, "skins", [&](const sb_json *o) {
        tinygltf::Skin s;
        s.inverseBindMatrices = int_of(o, "inverseBindMatrices", -1);
        s.skeleton = int_of(o, "skeleton", -1);
        s.joints = ints_of(o, "joints");
        m.skins.push_back(std::move(s));
    });
}

// The animations: their samplers and channels.
static void model_animations(const sb_json *root, tinygltf::Model &m) {
    each(root, "animations", [&](const sb_json *o) {
        tinygltf::Animation an;
        an.name = str_of(o, "name", "");
        each(o, "samplers", [&](const sb_json *q) {
            tinygltf::AnimationSampler s;
            s.input = int_of(q, "input", -1);
            s.output = int_of(q, "output", -1);
            s.interpolation = str_of(q, "interpolation", "LINEAR");
            an.samplers.push_back(s);
        });
        each(o, "channels", [&](const sb_json *q) {
            tinygltf::AnimationChannel c;
            const sb_json *t = member(q, "target");
            c.sampler = int_of(q, "sampler", -1);
            c.target_node = int_of(t, "node", -1);
            c.target_path = str_of(t, "path", "");
            an.channels.push_back(c);
        });
        m.animations.push_back(std::move(an));
    });
}

// The materials (the alpha test's part), textures, samplers and images.
static void model_materials(const sb_json *root, tinygltf::Model &m) {
    each(root, "materials", [&](const sb_json *o) {
        tinygltf::Material mat;
        mat.alphaMode = str_of(o, "alphaMode", "OPAQUE");
        mat.alphaCutoff = num_of(o, "alphaCutoff", 0.5);
        mat.doubleSided = bool_of(o, "doubleSided", false);
        const sb_json *pbr = member(o, "pbrMetallicRoughness");
        std::vector<double> f = nums_of(pbr, "baseColorFactor");
        if (f.size() == 4) mat.pbrMetallicRoughness.baseColorFactor = f;
        const sb_json *bt = member(pbr, "baseColorTexture");
        if (bt) {
            mat.pbrMetallicRoughness.baseColorTexture.index = int_of(bt, "index", -1);
            mat.pbrMetallicRoughness.baseColorTexture.texCoord = int_of(bt, "texCoord", 0);
            mat.pbrMetallicRoughness.baseColorTexture.extensions = extensions_of(bt);
        }
        m.materials.push_back(std::move(mat));
    });
    each(root, "textures", [&](const sb_json *o) {
        tinygltf::Texture t;
        t.source = int_of(o, "source", -1);
        t.sampler = int_of(o, "sampler", -1);
        m.textures.push_back(t);
    });
    each(root, "samplers", [&](const sb_json *o) {
        tinygltf::Sampler s;
        s.wrapS = int_of(o, "wrapS", TINYGLTF_TEXTURE_WRAP_REPEAT);
        s.wrapT = int_of(o, "wrapT", TINYGLTF_TEXTURE_WRAP_REPEAT);
        m.samplers.push_back(s);
    });
    each(root, "images", [&](const sb_json *) { m.images.emplace_back(); });
}

// The cameras, the lights (KHR_lights_punctual) and the scenes.
static void model_cameras_lights(const sb_json *root, tinygltf::Model &m) {
    each(root, "cameras", [&](const sb_json *o) {
        tinygltf::Camera c;
        c.type = str_of(o, "type", "");
        const sb_json *p = member(o, "perspective");
        if (p) {
            c.perspective.yfov = num_of(p, "yfov", 0);
            c.perspective.znear = num_of(p, "znear", 0);
            c.perspective.zfar = num_of(p, "zfar", 0);
            c.perspective.aspectRatio = num_of(p, "aspectRatio", 0);
        }
        m.cameras.push_back(c);
    });
    each(member(member(root, "extensions"), "KHR_lights_punctual"), "lights", [&](const sb_json *o) {
        tinygltf::Light l;
        l.type = str_of(o, "type", "");
        l.color = nums_of(o, "color");
        l.intensity = num_of(o, "intensity", 1.0);
        l.range = num_of(o, "range", 0.0);
        l.spot.outerConeAngle = num_of(member(o, "spot"), "outerConeAngle", SB_PI / 4);
        m.lights.push_back(l);
    });
    each(root, "scenes", [&](const sb_json *o) {
        tinygltf::Scene sc;
        sc.nodes = ints_of(o, "nodes");
        m.scenes.push_back(std::move(sc));
    });
    m.defaultScene = int_of(root, "scene", -1);
}

bool build_model(const sb_json *root, Source &src, const char *file, tinygltf::Model &m, Document &doc,
                 const sb_scene_opts *opts, ImageStore *images, sb_err *err) {
    if (!read_buffers(root, src, file, doc, err) || !model_accessors(root, file, m, err)) return false;
    model_meshes(root, m);
    model_animations(root, m);
    model_materials(root, m);
    model_cameras_lights(root, m);
    return read_images(root, src, file, m, doc, opts, images);
}

// Reads the file once, parses it once and checks that document (gltf_check.h), then fills tinygltf's model from
// it (build_model). *hash: of the file and the files it refers to. unused: where the check's notes go (NULL: not
// kept); camera >= 0: that camera is checked strictly (a path uses it).
bool load_model(const char *path, const sb_scene_opts *opts, tinygltf::Model &model, Document &docm,
                ImageStore *images, uint64_t *hash, char *unused, size_t unused_len, int camera, sb_err *err) {
    size_t size = 0;
    docm.map = sb_map_file(path, &docm.map_len, false);   // the file where it is: no copy
    if (!docm.map) {   // why not (no file, an empty one...), as reading it says
        char *text = sb_read_file(path, &size, err);
        free(text);
        return text ? sb_fail(err, "%s: an empty file", path) : false;
    }
    size = docm.map_len;
    const char *bytes = static_cast<const char *>(docm.map);
    if (size > UINT_MAX) return sb_fail(err, "%s: %zu bytes: files over 4 GiB are not supported", path, size);
    const unsigned char *u = reinterpret_cast<const unsigned char *>(bytes);
    bool glb = size >= 4 && memcmp(bytes, "glTF", 4) == 0;
    const char *json = bytes;
    uint64_t json_len = size, bin_len = 0;
    const unsigned char *bin = nullptr;
    uint64_t used = size;
    if (glb && !sb_glb_split(u, size, path, &json, &json_len, &bin, &bin_len, &used, unused, unused_len, err))
        return false;
    std::string base_dir(path);
    size_t slash = base_dir.find_last_of('/');
    base_dir = slash == std::string::npos ? std::string(".") : slash == 0 ? std::string("/") : base_dir.substr(0, slash);
    sb_json_doc doc;
    if (!sb_json_parse(&doc, path, json, json_len, err)) return false;
    sb_scene_opts no_opts;
    memset(&no_opts, 0, sizeof no_opts);
    sb_gltf_check_desc cd = {path, base_dir.c_str(), glb, bin ? bin_len : 0, opts && opts->allow_external_uris,
                             unused, unused_len};
    Source src{base_dir, cd.allow_external_uris, bin, bin_len, sb_hash_bytes(SB_FNV_SEED, bytes, size)};
    bool ok = sb_gltf_check(doc.root, &cd, err) &&
              (camera < 0 || sb_gltf_check_camera(doc.root, &cd, (uint64_t)camera, err)) &&
              build_model(doc.root, src, path, model, docm, opts ? opts : &no_opts, images, err);
    sb_json_free(&doc);
    if (ok) *hash = src.hash;
    return ok;
}

// What the file held that is not drawn as its author made it, said once at load.
void log_features(const char *path, const sb_scene *s, const tinygltf::Model &m, const ImageStore &images) {
    const sb_scene_features &f = s->features;
    if (f.undecodable_alpha)
        sb_log("%s: %u alpha texture(s) cannot be used (%s%s): those materials are alpha-tested with their base colour "
               "factor alone", path, f.undecodable_alpha, images.first_cause.c_str(),
               f.undecodable_alpha > 1 ? "; the first" : "");
    if (f.vertex_alpha_ignored)
        sb_log("%s: %u alpha-tested primitive(s) have vertex colours with alpha, which the alpha test leaves out", path,
               f.vertex_alpha_ignored);
    if (s->opts.pose && m.animations.empty())
        sb_log("%s: --pose %g: the file has no animation; nodes keep their own transforms", path, s->opts.pose_time);
}

void read_cameras(sb_scene *s, const tinygltf::Model &model) {
    s->camera_count = (uint32_t)model.cameras.size();
    s->cameras = (sb_scene_camera *)sb_xcalloc(s->camera_count ? s->camera_count : 1, sizeof(sb_scene_camera));
    for (size_t i = 0; i < model.cameras.size(); i++) {
        const tinygltf::Camera &cam = model.cameras[i];
        s->cameras[i].node = -1;
        if (cam.type == "perspective") {
            s->cameras[i].yfov = cam.perspective.yfov;
            s->cameras[i].znear = cam.perspective.znear;
            s->cameras[i].zfar = cam.perspective.zfar;
        }
    }
}

// The default scene's root nodes, or every parentless node when there is no scene.
bool scene_roots(const char *path, const tinygltf::Model &model, std::vector<int> &roots, sb_err *err) {
    int sc = model.defaultScene >= 0 ? model.defaultScene : 0;
    if (!model.scenes.empty()) {
        if (sc >= (int)model.scenes.size()) return sb_fail(err, "%s: /scene: scene %d does not exist", path, sc);
        roots = model.scenes[sc].nodes;
        return true;
    }
    std::vector<char> child(model.nodes.size());
    for (auto &n : model.nodes)
        for (int ch : n.children)
            if (ch >= 0 && ch < (int)child.size()) child[ch] = 1;
    for (size_t i = 0; i < model.nodes.size(); i++)
        if (!child[i]) roots.push_back((int)i);
    return true;
}

} // namespace

extern "C" bool sb_gltf_load(sb_scene *s, const char *path, const sb_scene_opts *opts, sb_err *err) {
    tinygltf::Model model;
    Document doc;
    ImageStore images;
    sb_scene_opts defaults;
    memset(&defaults, 0, sizeof defaults);
    if (!opts) opts = &defaults;
    try {
        uint64_t hash;
        double t0 = sb_now_ms();
        if (!load_model(path, opts, model, doc, &images, &hash, s->unused, sizeof s->unused, -1, err)) return false;
        if (s->unused[0]) sb_log("%s: left out, not refused: %s", path, s->unused);
        double t1 = sb_now_ms();
        s->load_part_ms[SB_LOAD_PARSE] = t1 - t0;
        Loader L{Ctx{path, &model, &doc, err}, s, opts, &images, {}, {}, {}, {}, {}, {}};
        read_cameras(s, model);
        std::vector<int> roots;
        bool ok = scene_roots(path, model, roots, err) && L.pose() && L.walk(roots) && L.clips();
        std::unique_ptr<sb_motion> motion(L.mo);   // freed on every way out but the scene's
        if (!ok) return false;
        L.reserve();
        if (!L.emit_nodes() || !L.anim_bound()) return false;
        if (motion && !motion->places.empty()) {
            s->motion = motion.release();
            s->motion_free = sb_motion_free;
        }
        s->features.textures_skipped = (uint32_t)model.images.size() - s->features.textures_decoded;
        s->content_hash = hash;
        s->features.clips = (uint32_t)model.animations.size();
        log_features(path, s, model, images);
        s->load_part_ms[SB_LOAD_FLATTEN] = sb_now_ms() - t1;
        return true;
    } catch (const std::exception &ex) {
        return sb_fail(err, "%s: %s", path, ex.what());
    }
}

// An animated glTF camera's keys at every animation time of the camera's node
// (translation/rotation channels of every animation), parent chain static.
extern "C" bool sb_gltf_camera_keys(sb_camera_keys *p, const char *path, int cam, const sb_scene_opts *opts,
                                    sb_err *err) {
    tinygltf::Model model;
    Document doc;
    ImageStore images;
    try {
        uint64_t hash;
        if (!load_model(path, opts, model, doc, &images, &hash, NULL, 0, cam, err)) return false;
        Ctx c{path, &model, &doc, err};
        if (cam < 0 || cam >= (int)model.cameras.size())
            return sb_fail(err, "%s#camera=%d: the file has %zu camera(s)", path, cam, model.cameras.size());
        int cn = -1;
        std::vector<int> parent(model.nodes.size(), -1);
        for (size_t i = 0; i < model.nodes.size(); i++) {
            if (model.nodes[i].camera == cam && cn < 0) cn = (int)i;
            for (int ch : model.nodes[i].children)
                if (ch >= 0 && ch < (int)parent.size()) parent[ch] = (int)i;
        }
        if (cn < 0) return sb_fail(err, "%s#camera=%d: no node uses this camera", path, cam);
        sb_m4 pw = sb_m4_identity();
        size_t depth = 0; // the graph was checked to be a forest: the walk ends at a root
        for (int q = parent[cn]; q >= 0 && depth <= model.nodes.size(); q = parent[q], depth++)
            pw = sb_m4_mul(node_local(model.nodes[q]), pw);
        std::vector<Channel> chans;
        std::vector<int> is_rot;
        for (size_t ai = 0; ai < model.animations.size(); ai++) {
            const auto &an = model.animations[ai];
            for (size_t ci = 0; ci < an.channels.size(); ci++) {
                const auto &ch = an.channels[ci];
                if (ch.target_node != cn || (ch.target_path != "translation" && ch.target_path != "rotation")) continue;
                chans.emplace_back();
                std::string where = "/animations/" + std::to_string(ai) + "/channels/" + std::to_string(ci);
                std::string skip;
                if (!read_channel(c, an, ch, where, ch.target_path == "rotation" ? 4 : 3, chans.back(), &skip))
                    return false;
                if (!skip.empty()) {   // the camera keeps its other channels
                    sb_log("%s: %s", path, skip.c_str());
                    chans.pop_back();
                }
            }
        }
        std::set<double> times;
        for (const Channel &ch : chans) times.insert(ch.in.begin(), ch.in.end());
        if (times.empty()) times.insert(0.0);
        const tinygltf::Camera &camera = model.cameras[cam];
        p->fov_deg = camera.type == "perspective" && camera.perspective.yfov > 0 ? camera.perspective.yfov * 180 / SB_PI : 0;
        if (camera.type == "perspective") {
            p->znear = camera.perspective.znear;
            p->zfar = camera.perspective.zfar;
        }
        p->key_count = (int)times.size();
        p->keys = (sb_camera_key *)sb_xcalloc(p->key_count, sizeof(sb_camera_key));
        double t0 = *times.begin();
        int ki = 0;
        for (double t : times) {
            sb_trs x = node_trs(model.nodes[cn]);
            bool animated = false;
            for (Channel &ch : chans) { // later channels win, as in a player applying them in order
                sb_anim_sample(&ch.s, t, ch.s.rotation ? x.r : x.t);
                animated = true;
            }
            sb_m4 w = sb_m4_mul(pw, animated || model.nodes[cn].matrix.size() != 16 ? sb_trs_matrix(&x)
                                                                                    : node_local(model.nodes[cn]));
            sb_camera_key &k = p->keys[ki++];
            k.t = t - t0;
            k.pos = sb_m4_point(w, sb_v3_make(0, 0, 0));
            sb_v3 f = sb_v3_norm(sb_m4_dir(w, sb_v3_make(0, 0, -1)));
            sb_v3 u = sb_v3_norm(sb_m4_dir(w, sb_v3_make(0, 1, 0)));
            k.rot = sb_quat_look(f, u);
            if (!sb_v3_finite(k.pos)) return sb_fail(err, "%s#camera=%d: camera transform is not finite at t=%g", path, cam, t);
        }
        return true;
    } catch (const std::exception &ex) {
        return sb_fail(err, "%s: %s", path, ex.what());
    }
}

