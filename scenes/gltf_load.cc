// gltf_load.cc - the tinygltf adapter: glTF 2.0 (.gltf/.glb) into the flat C
// scene model, and animated glTF cameras into paths. The only C++ on the
// scene side; everything it exposes is a C function.
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>
#include <set>
#include <algorithm>
#include <memory>

#include <tiny_gltf.h>

extern "C" {
#include "gltf_check.h"
#include "path.h"
#include "scene.h"
}

namespace {

struct ImageCounter {
    unsigned skipped = 0;
};

// Shadows do not need textures: keep the bytes undecoded (webp included).
bool skip_image(tinygltf::Image *, const int, std::string *, std::string *, int, int,
                const unsigned char *, int, void *user) {
    static_cast<ImageCounter *>(user)->skipped++;
    return true;
}

std::string first_line(const std::string &s) {
    std::string r = s.substr(0, s.find('\n'));
    while (!r.empty() && (r.back() == '\r' || r.back() == ' ')) r.pop_back();
    return r;
}

struct Ctx {
    const char *file;
    const tinygltf::Model *m;
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
    if (bv.buffer < 0 || bv.buffer >= (int)m.buffers.size())
        return c.fail("/bufferViews/" + std::to_string(view) + "/buffer", "missing or out of range");
    const tinygltf::Buffer &b = m.buffers[bv.buffer];
    if (!fits(bv.byteOffset, bv.byteLength, b.data.size()))
        return c.fail("/bufferViews/" + std::to_string(view), "range exceeds buffer " + std::to_string(bv.buffer) +
                                                                 " of " + std::to_string(b.data.size()) + " bytes");
    size_t need;
    if (count == 0 || __builtin_mul_overflow(stride, count - 1, &need) || __builtin_add_overflow(need, elem, &need) ||
        !fits(off, need, bv.byteLength))
        return c.fail(where, "count " + std::to_string(count) + " runs past the end of bufferView " + std::to_string(view));
    *data = b.data.data() + bv.byteOffset + off;
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
    out.assign(total, 0.0);
    auto decode = [&](const unsigned char *d, size_t stride, size_t n, size_t first) {
        for (size_t i = 0; i < n; i++)
            for (int k = 0; k < ncomp; k++)
                out[(first + i) * ncomp + k] =
                    component(d + i * stride + (size_t)(k / rows) * col + (size_t)(k % rows) * csize, a.componentType, a.normalized);
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
    if (a.sparse.isSparse) {
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
            decode(dv + (size_t)k * elem, elem, 1, idx);
            prev = idx;
        }
    }
    return true;
}

bool read_vec(Ctx &c, int acc, const std::string &where, int ncomp, std::vector<double> &out) {
    int type = ncomp == 1 ? TINYGLTF_TYPE_SCALAR : ncomp == 3 ? TINYGLTF_TYPE_VEC3 : TINYGLTF_TYPE_VEC4;
    if (!read_accessor(c, acc, where, type, out)) return false;
    for (size_t i = 0; i < out.size(); i++)
        if (!std::isfinite(out[i]))
            return c.fail(where, "element " + std::to_string(i / ncomp) + " is " + (std::isnan(out[i]) ? "NaN" : "Inf"));
    return true;
}

bool read_indices(Ctx &c, int acc, const std::string &where, std::vector<uint32_t> &out) {
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

sb_m4 node_local(const tinygltf::Node &n) {
    if (n.matrix.size() == 16) {
        sb_m4 r;
        for (int i = 0; i < 16; i++) r.m[i] = n.matrix[i];
        return r;
    }
    sb_m4 t = sb_m4_identity(), r = sb_m4_identity(), s = sb_m4_identity();
    if (n.translation.size() == 3) t = sb_m4_translate(sb_v3_make(n.translation[0], n.translation[1], n.translation[2]));
    if (n.rotation.size() == 4)
        r = sb_quat_to_m4(sb_quat_norm({n.rotation[0], n.rotation[1], n.rotation[2], n.rotation[3]}));
    if (n.scale.size() == 3) s = sb_m4_scale(sb_v3_make(n.scale[0], n.scale[1], n.scale[2]));
    return sb_m4_mul(t, sb_m4_mul(r, s));
}

struct Loader {
    Ctx c;
    sb_scene *s;
    std::vector<sb_m4> world;   // per node, filled during traversal
    std::vector<char> visited;

    bool prim(int node, int mesh, int pi, const sb_m4 &w) {
        const tinygltf::Model &m = *c.m;
        const tinygltf::Primitive &p = m.meshes[mesh].primitives[pi];
        std::string where = "/meshes/" + std::to_string(mesh) + "/primitives/" + std::to_string(pi);
        if (p.mode < 0 || p.mode > 6) return c.fail(where + "/mode", "unsupported primitive mode " + std::to_string(p.mode));
        if (p.mode < 4) return true; // points and lines neither cast nor receive shadows
        auto pit = p.attributes.find("POSITION");
        if (pit == p.attributes.end()) return c.fail(where + "/attributes", "no POSITION");
        std::vector<double> pos, nrm;
        if (!read_vec(c, pit->second, where + "/attributes/POSITION", 3, pos)) return false;
        size_t nv = pos.size() / 3;
        auto nit = p.attributes.find("NORMAL");
        bool have_n = nit != p.attributes.end();
        if (have_n) {
            if (!read_vec(c, nit->second, where + "/attributes/NORMAL", 3, nrm)) return false;
            if (nrm.size() != pos.size()) return c.fail(where + "/attributes/NORMAL", "count differs from POSITION");
        }
        std::vector<uint32_t> idx;
        if (p.indices >= 0) {
            if (!read_indices(c, p.indices, where + "/indices", idx)) return false;
        } else {
            idx.resize(nv);
            for (size_t i = 0; i < nv; i++) idx[i] = (uint32_t)i;
        }
        for (size_t i = 0; i < idx.size(); i++)
            if (idx[i] >= nv)
                return c.fail(where + "/indices", "index " + std::to_string(idx[i]) + " at " + std::to_string(i) +
                                                      " is out of range (" + std::to_string(nv) + " vertices)");
        std::vector<uint32_t> tris;
        if (p.mode == 4) {
            tris.assign(idx.begin(), idx.begin() + (idx.size() / 3) * 3);
        } else if (p.mode == 5) {
            for (size_t i = 2; i < idx.size(); i++) {
                if (i % 2 == 0) tris.insert(tris.end(), {idx[i - 2], idx[i - 1], idx[i]});
                else tris.insert(tris.end(), {idx[i - 1], idx[i - 2], idx[i]});
            }
        } else {
            for (size_t i = 2; i < idx.size(); i++) tris.insert(tris.end(), {idx[0], idx[i - 1], idx[i]});
        }
        if (tris.empty()) return true;
        double det = w.m[0] * (w.m[5] * w.m[10] - w.m[9] * w.m[6]) - w.m[4] * (w.m[1] * w.m[10] - w.m[9] * w.m[2]) +
                     w.m[8] * (w.m[1] * w.m[6] - w.m[5] * w.m[2]);
        if (det < 0)
            for (size_t i = 0; i < tris.size(); i += 3) std::swap(tris[i + 1], tris[i + 2]);
        sb_m4 nm = sb_m4_identity();
        if (have_n) {
            sb_m4 inv;
            if (sb_m4_invert(w, &inv)) { // inverse transpose of the upper 3x3
                for (int r = 0; r < 3; r++)
                    for (int col = 0; col < 3; col++) nm.m[col * 4 + r] = inv.m[r * 4 + col];
            }
        }
        std::vector<double> wp(nv * 3), wn;
        for (size_t v = 0; v < nv; v++) {
            sb_v3 q = sb_m4_point(w, sb_v3_make(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]));
            wp[3 * v] = q.x; wp[3 * v + 1] = q.y; wp[3 * v + 2] = q.z;
        }
        if (have_n) {
            wn.resize(nv * 3);
            for (size_t v = 0; v < nv; v++) {
                sb_v3 q = sb_m4_dir(nm, sb_v3_make(nrm[3 * v], nrm[3 * v + 1], nrm[3 * v + 2]));
                wn[3 * v] = q.x; wn[3 * v + 1] = q.y; wn[3 * v + 2] = q.z;
            }
        }
        sb_prim_desc d;
        memset(&d, 0, sizeof d);
        d.positions = wp.data();
        d.normals = have_n ? wn.data() : nullptr;
        d.vertex_count = (uint32_t)nv;
        d.indices = tris.data();
        d.index_count = (uint32_t)tris.size();
        d.color[0] = d.color[1] = d.color[2] = d.color[3] = 1.0f;
        d.node = (uint32_t)node;
        if (p.material >= 0) {
            if (p.material >= (int)m.materials.size())
                return c.fail(where + "/material", "material " + std::to_string(p.material) + " does not exist");
            const tinygltf::Material &mat = m.materials[p.material];
            const auto &f = mat.pbrMetallicRoughness.baseColorFactor;
            for (int k = 0; k < 4 && k < (int)f.size(); k++) d.color[k] = (float)f[k];
            d.alpha_mask = mat.alphaMode == "MASK";
            d.alpha_cutoff = (float)mat.alphaCutoff;
        }
        sb_scene_add_prim(s, &d);
        return true;
    }

    // One node: its world transform from its parent's, its primitives, camera and light.
    bool visit(int ni, const sb_m4 &parent) {
        const tinygltf::Model &m = *c.m;
        std::string where = "/nodes/" + std::to_string(ni);
        const tinygltf::Node &n = m.nodes[ni];
        if ((!n.matrix.empty() && n.matrix.size() != 16) || (!n.translation.empty() && n.translation.size() != 3) ||
            (!n.rotation.empty() && n.rotation.size() != 4) || (!n.scale.empty() && n.scale.size() != 3))
            return c.fail(where, "matrix/translation/rotation/scale has the wrong length");
        sb_m4 w = sb_m4_mul(parent, node_local(n));
        if (!sb_m4_finite(w)) return c.fail(where, "transform is not finite");
        world[ni] = w;
        if (n.mesh >= 0) {
            if (n.mesh >= (int)m.meshes.size()) return c.fail(where + "/mesh", "mesh " + std::to_string(n.mesh) + " does not exist");
            s->nodes_drawn++;
            for (size_t pi = 0; pi < m.meshes[n.mesh].primitives.size(); pi++)
                if (!prim(ni, n.mesh, (int)pi, w)) return false;
        }
        if (n.camera >= 0 && n.camera < (int)s->camera_count) s->cameras[n.camera].node = ni;
        auto ext = n.extensions.find("KHR_lights_punctual");
        if (ext != n.extensions.end() && ext->second.Has("light")) {
            int li = ext->second.Get("light").GetNumberAsInt();
            if (li < 0 || li >= (int)m.lights.size())
                return c.fail(where + "/extensions/KHR_lights_punctual/light", "light " + std::to_string(li) + " does not exist");
            const tinygltf::Light &L = m.lights[li];
            sb_light l;
            memset(&l, 0, sizeof l);
            l.type = L.type == "directional" ? SB_LIGHT_DIRECTIONAL : L.type == "spot" ? SB_LIGHT_SPOT : SB_LIGHT_POINT;
            l.position = sb_m4_point(w, sb_v3_make(0, 0, 0));
            l.direction = sb_v3_norm(sb_m4_dir(w, sb_v3_make(0, 0, -1)));
            for (int k = 0; k < 3; k++) l.color[k] = k < (int)L.color.size() ? (float)L.color[k] : 1.0f;
            l.intensity = L.intensity;
            l.range = L.range;
            s->lights = (sb_light *)sb_xrealloc(s->lights, (s->light_count + 1) * sizeof(sb_light));
            s->lights[s->light_count++] = l;
            if (l.type == SB_LIGHT_DIRECTIONAL && !s->has_sun) {
                s->has_sun = true;
                s->sun = sb_v3_scale(l.direction, -1);
            }
        }
        return true;
    }

    // Depth-first from the roots without recursion (exported files hold chains
    // of tens of thousands of nodes), in the order a recursive walk would take.
    bool walk(const std::vector<int> &roots) {
        const tinygltf::Model &m = *c.m;
        struct Item { int node; sb_m4 parent; };
        std::vector<Item> stack;
        for (size_t i = roots.size(); i-- > 0;) stack.push_back({roots[i], sb_m4_identity()});
        while (!stack.empty()) {
            Item it = stack.back();
            stack.pop_back();
            std::string where = "/nodes/" + std::to_string(it.node);
            if (it.node < 0 || it.node >= (int)m.nodes.size()) return c.fail(where, "node does not exist");
            if (visited[it.node]) return c.fail(where, "node is reached twice (a cycle or a node with two parents)");
            visited[it.node] = 1;
            if (!visit(it.node, it.parent)) return false;
            const std::vector<int> &ch = m.nodes[it.node].children;
            for (size_t i = ch.size(); i-- > 0;) stack.push_back({ch[i], world[it.node]});
        }
        return true;
    }
};

// tinygltf reads external buffers and images through these: only regular
// files inside the scene's folder (unless allowed), never shell expansion.
struct FsCtx {
    std::string base_dir;
    bool allow_external;
};

bool fs_exists(const std::string &path, void *user) {
    FsCtx *f = static_cast<FsCtx *>(user);
    char real[PATH_MAX];
    sb_err e;
    return sb_file_confined(f->base_dir.c_str(), path.c_str(), f->allow_external, real, sizeof real, &e);
}

std::string fs_expand(const std::string &path, void *) { return path; }

bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *user) {
    FsCtx *f = static_cast<FsCtx *>(user);
    char real[PATH_MAX];
    sb_err e;
    size_t n = 0;
    char *data = nullptr;
    if (sb_file_confined(f->base_dir.c_str(), path.c_str(), f->allow_external, real, sizeof real, &e))
        data = sb_read_file(real, &n, &e);
    if (!data) {
        if (err) *err = e.msg;
        return false;
    }
    out->assign(data, data + n);
    free(data);
    return true;
}

bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *) {
    if (err) *err = "shadowbench writes no glTF files";
    return false;
}

// Reads the file once, checks the raw document (gltf_check.h), then lets
// tinygltf parse it from memory. *hash: FNV-1a of the file and its buffers.
bool load_model(const char *path, const sb_scene_opts *opts, tinygltf::Model &model, ImageCounter *images,
                uint64_t *hash, sb_err *err) {
    size_t size = 0;
    char *bytes = sb_read_file(path, &size, err);
    if (!bytes) return false;
    std::unique_ptr<char, decltype(&free)> hold(bytes, &free);
    if (size > UINT_MAX) return sb_fail(err, "%s: %zu bytes: files over 4 GiB are not supported", path, size);
    const unsigned char *u = reinterpret_cast<const unsigned char *>(bytes);
    bool glb = size >= 4 && memcmp(bytes, "glTF", 4) == 0;
    const char *json = bytes;
    uint64_t json_len = size, bin_len = 0;
    const unsigned char *bin = nullptr;
    if (glb && !sb_glb_split(u, size, path, &json, &json_len, &bin, &bin_len, err)) return false;
    std::string base_dir(path);
    size_t slash = base_dir.find_last_of('/');
    base_dir = slash == std::string::npos ? std::string(".") : slash == 0 ? std::string("/") : base_dir.substr(0, slash);
    sb_json_doc doc;
    if (!sb_json_parse(&doc, path, json, json_len, err)) return false;
    sb_gltf_check_desc cd = {path, base_dir.c_str(), glb, bin ? bin_len : 0, opts && opts->allow_external_uris};
    bool ok = sb_gltf_check(doc.root, &cd, err);
    sb_json_free(&doc);
    if (!ok) return false;

    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skip_image, images);
    FsCtx fs_ctx{base_dir, cd.allow_external_uris};
    loader.SetFsCallbacks(tinygltf::FsCallbacks{fs_exists, fs_expand, fs_read, fs_write, &fs_ctx});
    std::string e, w;
    ok = glb ? loader.LoadBinaryFromMemory(&model, &e, &w, u, (unsigned)size, base_dir)
             : loader.LoadASCIIFromString(&model, &e, &w, bytes, (unsigned)size, base_dir);
    if (!ok) return sb_fail(err, "%s: %s", path, e.empty() ? "not a valid glTF file" : first_line(e).c_str());
    uint64_t h = sb_fnv1a(SB_FNV_SEED, bytes, size);
    for (auto &b : model.buffers) h = sb_fnv1a(h, b.data.data(), b.data.size());
    *hash = h;
    return true;
}

} // namespace

extern "C" bool sb_gltf_load(sb_scene *s, const char *path, const sb_scene_opts *opts, sb_err *err) {
    tinygltf::Model model;
    ImageCounter images;
    try {
        uint64_t hash;
        if (!load_model(path, opts, model, &images, &hash, err)) return false;
        Loader L{Ctx{path, &model, err}, s, std::vector<sb_m4>(model.nodes.size()), std::vector<char>(model.nodes.size())};
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
        std::vector<int> roots;
        int sc = model.defaultScene >= 0 ? model.defaultScene : 0;
        if (!model.scenes.empty()) {
            if (sc >= (int)model.scenes.size()) return sb_fail(err, "%s: /scene: scene %d does not exist", path, sc);
            roots = model.scenes[sc].nodes;
        } else { // no scenes: every node without a parent is a root
            std::vector<char> child(model.nodes.size());
            for (auto &n : model.nodes)
                for (int ch : n.children)
                    if (ch >= 0 && ch < (int)child.size()) child[ch] = 1;
            for (size_t i = 0; i < model.nodes.size(); i++)
                if (!child[i]) roots.push_back((int)i);
        }
        if (!L.walk(roots)) return false;
        s->images_skipped = images.skipped;
        s->content_hash = hash;
        if (s->alpha_mask_draws)
            sb_log("%s: %u alpha-masked primitive(s) are drawn as opaque casters (alpha textures are not applied)",
                   path, s->alpha_mask_draws);
        if (images.skipped)
            sb_log("%s: %u texture(s) not decoded (shadows need none)%s", path, images.skipped,
                   model.extensionsRequired.empty() ? "" : "; required extensions ignored for geometry");
        return true;
    } catch (const std::exception &ex) {
        return sb_fail(err, "%s: %s", path, ex.what());
    }
}

// An animated glTF camera as a path: keys at every animation time of the
// camera's node (translation/rotation channels), parent chain static.
extern "C" bool sb_gltf_camera_path(sb_path *p, const char *path, int cam, const sb_scene_opts *opts, sb_err *err) {
    tinygltf::Model model;
    ImageCounter images;
    try {
        uint64_t hash;
        if (!load_model(path, opts, model, &images, &hash, err)) return false;
        Ctx c{path, &model, err};
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
        const tinygltf::Node &n = model.nodes[cn];
        struct Chan { std::vector<double> in, out; int ncomp; bool step; };
        Chan tr{{}, {}, 3, false}, rot{{}, {}, 4, false};
        bool have_t = false, have_r = false;
        for (size_t ai = 0; ai < model.animations.size(); ai++) {
            const auto &an = model.animations[ai];
            for (size_t ci = 0; ci < an.channels.size(); ci++) {
                const auto &ch = an.channels[ci];
                if (ch.target_node != cn) continue;
                bool is_t = ch.target_path == "translation", is_r = ch.target_path == "rotation";
                if (!is_t && !is_r) continue;
                std::string where = "/animations/" + std::to_string(ai) + "/channels/" + std::to_string(ci);
                if (ch.sampler < 0 || ch.sampler >= (int)an.samplers.size()) return c.fail(where, "sampler out of range");
                const auto &smp = an.samplers[ch.sampler];
                Chan &dst = is_t ? tr : rot;
                if (!read_vec(c, smp.input, where + "/input", 1, dst.in)) return false;
                if (!read_vec(c, smp.output, where + "/output", dst.ncomp, dst.out)) return false;
                size_t k = dst.in.size();
                if (smp.interpolation == "CUBICSPLINE") { // keep the values, drop the tangents
                    if (dst.out.size() != 3 * k * dst.ncomp) return c.fail(where, "CUBICSPLINE output count mismatch");
                    std::vector<double> v(k * dst.ncomp);
                    for (size_t i = 0; i < k; i++)
                        for (int j = 0; j < dst.ncomp; j++) v[i * dst.ncomp + j] = dst.out[(3 * i + 1) * dst.ncomp + j];
                    dst.out = v;
                }
                if (dst.out.size() != k * dst.ncomp) return c.fail(where, "input and output counts differ");
                for (size_t i = 1; i < k; i++)
                    if (!(dst.in[i] > dst.in[i - 1])) return c.fail(where + "/input", "times must increase");
                dst.step = smp.interpolation == "STEP";
                (is_t ? have_t : have_r) = true;
            }
        }
        std::set<double> times;
        for (double t : tr.in) times.insert(t);
        for (double t : rot.in) times.insert(t);
        if (times.empty()) times.insert(0.0);
        auto sample = [](const Chan &ch, double t, double *out) {
            size_t k = ch.in.size();
            size_t i = std::upper_bound(ch.in.begin(), ch.in.end(), t) - ch.in.begin();
            if (i == 0 || i >= k || ch.step) {
                size_t j = i == 0 ? 0 : i - 1;
                for (int c2 = 0; c2 < ch.ncomp; c2++) out[c2] = ch.out[j * ch.ncomp + c2];
                return;
            }
            double u = (t - ch.in[i - 1]) / (ch.in[i] - ch.in[i - 1]);
            if (ch.ncomp == 4) {
                const double *a = &ch.out[(i - 1) * 4], *b = &ch.out[i * 4];
                sb_quat q = sb_quat_slerp(sb_quat_norm({a[0], a[1], a[2], a[3]}), sb_quat_norm({b[0], b[1], b[2], b[3]}), u);
                out[0] = q.x; out[1] = q.y; out[2] = q.z; out[3] = q.w;
            } else {
                for (int c2 = 0; c2 < ch.ncomp; c2++)
                    out[c2] = ch.out[(i - 1) * ch.ncomp + c2] * (1 - u) + ch.out[i * ch.ncomp + c2] * u;
            }
        };
        const tinygltf::Camera &camera = model.cameras[cam];
        p->fov_deg = camera.type == "perspective" && camera.perspective.yfov > 0 ? camera.perspective.yfov * 180 / SB_PI : 60;
        if (camera.type == "perspective") {
            p->znear = camera.perspective.znear;
            p->zfar = camera.perspective.zfar;
        }
        p->key_count = (int)times.size();
        p->keys = (sb_path_key *)sb_xcalloc(p->key_count, sizeof(sb_path_key));
        double t0 = *times.begin();
        int ki = 0;
        for (double t : times) {
            tinygltf::Node local = n;
            double v[4];
            if (have_t) { sample(tr, t, v); local.translation = {v[0], v[1], v[2]}; local.matrix.clear(); }
            if (have_r) { sample(rot, t, v); local.rotation = {v[0], v[1], v[2], v[3]}; local.matrix.clear(); }
            sb_m4 w = sb_m4_mul(pw, node_local(local));
            sb_path_key &k = p->keys[ki++];
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
