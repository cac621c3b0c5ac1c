// motion.cc - a scene's clips as they play (motion.h): the nodes' transforms at a clip time, every moving
// placement posed again (morph targets, skin or node transform) and written into the scene, its boxes, bounds
// and BVH made true to the pose. C++ for the data the glTF adapter leaves it (motion_data.h); everything it
// exposes is a C function.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <algorithm>
#include <atomic>
#include <map>
#include <memory>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

#include "motion_data.h"

extern "C" {
#include "blob.h"
#include "motion.h"
}

namespace {

// One channel at clip time t, into the node's transform or weights.
void sample_channel(sb_motion &m, sbm::MoChannel &c, double t) {
    const sbm::MoClip &cl = m.clips[c.clip];
    double ct = cl.duration > 0 ? fmod(t, cl.duration) : 0;
    if (ct < 0) ct += cl.duration;
    double v[64];
    sb_anim_sample(&c.ch.s, ct, v);
    if (c.path == sbm::PATH_W) {
        m.weights[c.node].assign(v, v + c.ch.s.ncomp);
        return;
    }
    double *dst = c.path == sbm::PATH_T ? m.trs[c.node].t : c.path == sbm::PATH_R ? m.trs[c.node].r : m.trs[c.node].s;
    memcpy(dst, v, sizeof(double) * (c.path == sbm::PATH_R ? 4 : 3));
}

// A moving node's world transform (its parent's made first).
void world_of(sb_motion &m, int ni) {
    sb_m4 local = m.anim[ni] || !m.has_matrix[ni] ? sb_trs_matrix(&m.trs[ni]) : m.rest_local[ni];
    m.world[ni] = m.parent[ni] < 0 ? local : sb_m4_mul(m.world[m.parent[ni]], local);
}

// Once: the rest pose (every clip's channels play at each pose, each writing the same field of the same node, so
// the rest stays where none writes), which nodes move (a channel's or under one) and the still ones' world
// matrices, made here only.
void motion_prepare_nodes(sb_motion &m) {
    size_t n = m.parent.size();
    m.trs = m.rest;
    m.weights = m.rest_weights;
    m.anim.assign(n, 0);
    for (const sbm::MoChannel &c : m.channels)
        if (c.path != sbm::PATH_W) m.anim[c.node] = 1;
    m.moving.assign(n, 0);
    m.world.resize(n);
    for (int ni : m.topo) {
        m.moving[ni] = m.anim[ni] || (m.parent[ni] >= 0 && m.moving[m.parent[ni]]);
        world_of(m, ni);
    }
}

} // namespace

namespace sbm {
// A few threads kept for the poses' work, asleep between them (nothing of theirs runs in a timed frame): run(n, f)
// calls f(0..n-1) on n of them (the caller is 0) and returns when all have.
class Workers {
public:
    explicit Workers(unsigned extra) {
        for (unsigned i = 0; i < extra; i++) th_.emplace_back([this, i] { loop(i + 1); });
    }
    ~Workers() {
        {
            std::lock_guard<std::mutex> l(mu_);
            quit_ = true;
        }
        wake_.notify_all();
        for (std::thread &t : th_) t.join();
    }
    unsigned size() const { return (unsigned)th_.size() + 1; }
    void run(unsigned n, const std::function<void(unsigned)> &f) {
        n = std::max(1u, std::min(n, size()));
        if (n > 1) {
            std::lock_guard<std::mutex> l(mu_);
            job_ = &f, want_ = n, busy_ = n - 1, gen_++;
        }
        if (n > 1) wake_.notify_all();
        f(0);
        if (n == 1) return;
        std::unique_lock<std::mutex> l(mu_);
        done_.wait(l, [this] { return busy_ == 0; });
    }

private:
    void loop(unsigned me) {
        uint64_t seen = 0;
        std::unique_lock<std::mutex> l(mu_);
        for (;;) {
            wake_.wait(l, [&] { return quit_ || gen_ != seen; });
            if (quit_) return;
            seen = gen_;
            if (me >= want_) continue;   // a job for fewer threads than there are
            const std::function<void(unsigned)> *f = job_;
            l.unlock();
            (*f)(me);
            l.lock();
            if (--busy_ == 0) done_.notify_one();
        }
    }
    std::vector<std::thread> th_;
    std::mutex mu_;
    std::condition_variable wake_, done_;
    const std::function<void(unsigned)> *job_ = nullptr;
    unsigned want_ = 0, busy_ = 0;
    uint64_t gen_ = 0;
    bool quit_ = false;
};
} // namespace sbm

namespace {

// Once (after motion_bounds_prepare): the pose's work in groups that share no node, so that each group is one
// thread's: a group is a top moving node (moving, its parent not), its channels, the moving nodes under it and the
// GPU-posed placements that read only its nodes (or still ones). What reads two groups, or a node that only a
// weights channel moves, is done alone: those channels before the groups, those placements after them.
void motion_prepare_groups(sb_motion &m) {
    size_t n = m.parent.size();
    std::vector<int> group(n, -1);
    m.groups.clear();
    for (int ni : m.topo) {
        if (!m.moving[ni]) continue;
        int p = m.parent[ni];
        if (p >= 0 && m.moving[p]) {
            group[ni] = group[p];
        } else {
            group[ni] = (int)m.groups.size();
            m.groups.emplace_back();
        }
        m.groups[group[ni]].nodes.push_back(ni);
    }
    std::vector<char> weighted(n, 0);   // a weights channel writes it
    m.lone_channels.clear(), m.lone_places.clear();
    for (size_t c = 0; c < m.channels.size(); c++) {
        int ni = m.channels[c].node;
        if (m.channels[c].path == sbm::PATH_W) weighted[ni] = 1;
        if (group[ni] >= 0) m.groups[group[ni]].channels.push_back((uint32_t)c);
        else m.lone_channels.push_back((uint32_t)c);
    }
    for (size_t k = 0; k < m.places.size(); k++) {
        const sbm::MoPlace &p = m.places[k];
        if (!p.gpu) continue;
        int g = -2;   // -2: none read yet; -1: two groups, or a node only weights move
        auto reads = [&](int ni) {
            int h = group[ni] >= 0 ? group[ni] : weighted[ni] ? -1 : -2;
            if (h == -2 || g == -1) return;
            g = g == -2 || g == h ? h : -1;
        };
        reads(p.node);
        if (p.skin >= 0)
            for (int j : m.skin_joints[p.skin]) reads(j);
        if (g >= 0) m.groups[g].places.push_back((uint32_t)k);
        else m.lone_places.push_back((uint32_t)k);
    }
    m.groups_ready = true;
}

void bound_place(const sb_motion &m, const sbm::MoPlace &p, sb_scene *s, std::vector<sb_m4> &jm);
void motion_bounds_prepare(sb_motion &m, const sb_scene *s);

// The motion's threads, made at their first use (none on a machine of one core), at most 16 with the caller's; f
// on n of them (f(0) alone where there are none or n is 1).
void in_parallel(sb_motion &m, unsigned n, const std::function<void(unsigned)> &f) {
    unsigned cores = std::max(1u, std::min(16u, std::thread::hardware_concurrency()));
    if (n > 1 && !m.workers && cores > 1) m.workers = new sbm::Workers(cores - 1);
    if (n > 1 && m.workers) m.workers->run(n, f);
    else f(0);
}

// The nodes' world transforms at clip time t, each clip's channels sampled at t modulo its duration; with boxes (s
// itself, writable), the GPU-posed placements' boxes too (bound_place). The groups go to the motion's threads, a
// few groups each.
void motion_nodes(sb_motion &m, double t, const sb_scene *s, sb_scene *boxes) {
    if (m.moving.size() != m.parent.size()) motion_prepare_nodes(m);
    if (!m.bounds_ready) motion_bounds_prepare(m, s);
    if (!m.groups_ready) motion_prepare_groups(m);
    for (uint32_t c : m.lone_channels) sample_channel(m, m.channels[c], t);
    std::atomic<size_t> next(0);
    const size_t count = m.groups.size(), grain = 2;   // groups a thread takes at a time
    in_parallel(m, (unsigned)((count + grain - 1) / grain), [&](unsigned) {
        std::vector<sb_m4> jm;
        for (size_t i; (i = next.fetch_add(grain)) < count;)
            for (size_t k = i; k < std::min(count, i + grain); k++) {
                const sb_motion::Group &g = m.groups[k];
                for (uint32_t c : g.channels) sample_channel(m, m.channels[c], t);
                for (int ni : g.nodes) world_of(m, ni);
                if (boxes)
                    for (uint32_t p : g.places) bound_place(m, m.places[p], boxes, jm);
            }
    });
    if (boxes) {
        std::vector<sb_m4> jm;
        for (uint32_t p : m.lone_places) bound_place(m, m.places[p], boxes, jm);
    }
    m.nodes_t = t;
}

// A skinned placement's joint j's matrix (world x inverse bind), and a rigid one's (node x instance).
sb_m4 joint_matrix(const sb_motion &m, const sbm::MoPlace &p, size_t j) {
    return sb_m4_mul(m.world[m.skin_joints[p.skin][j]], m.skin_ibm[p.skin][j]);
}
sb_m4 rigid_matrix(const sb_motion &m, const sbm::MoPlace &p) { return sb_m4_mul(m.world[p.node], p.inst); }

const sb_aabb EMPTY_BOX = {{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};

void grow(sb_aabb &b, sb_v3 p) { b.lo = sb_v3_min(b.lo, p), b.hi = sb_v3_max(b.hi, p); }

// Each placement's bounds that follow the joints, once: per draw, the box in the mesh's own space of the vertices
// each joint weighs (a rigid placement's: one box), and whether a vertex no joint weighs lies there. A skinned
// vertex is sum_j w_j M_j v / sum_j w_j (sb_m4_point divides by the summed matrix's w): with no weight negative,
// a mean of points each inside its joint's carried box, so inside their union; a placement with a negative weight,
// or without normals (the CPU makes its face normals), stays with the CPU and its exact boxes.
void motion_bounds_prepare(sb_motion &m, const sb_scene *s) {
    for (sbm::MoPlace &p : m.places) {
        const sbm::RestData &b = p.base;
        p.gpu = b.have_n;
        for (int set = 0; set < b.skin_sets; set++)
            for (double w : b.weights[set]) p.gpu = p.gpu && w >= 0;
        p.tbox.assign(p.dpos.size(), EMPTY_BOX);
        for (size_t t = 0; t < p.dpos.size(); t++) {
            grow(p.tbox[t], sb_v3_make(0, 0, 0));   // a vertex the target leaves out: no delta
            for (size_t i = 0; i + 2 < p.dpos[t].size(); i += 3)
                grow(p.tbox[t], sb_v3_make(p.dpos[t][i], p.dpos[t][i + 1], p.dpos[t][i + 2]));
        }
        size_t nj = p.skin >= 0 ? m.skin_joints[p.skin].size() : 0;
        std::vector<int> slot(nj + 1);
        p.dbox.assign(p.draws.size(), {});
        p.at_zero.assign(p.draws.size(), 0);
        for (size_t k = 0; k < p.draws.size(); k++) {
            const sb_draw &dr = s->draws[p.draws[k]];
            std::fill(slot.begin(), slot.end(), -1);
            std::vector<sbm::JointBox> &boxes = p.dbox[k];
            for (uint32_t i = 0; i < dr.index_count; i++) {
                uint32_t v = s->indices[dr.first_index + i] - p.first;
                if (v >= p.count) continue;
                sb_v3 q = sb_v3_make(b.pos[3 * v], b.pos[3 * v + 1], b.pos[3 * v + 2]);
                double sum = 0;
                for (int set = 0; set < (p.skin >= 0 ? b.skin_sets : 0); set++)
                    for (int c = 0; c < 4; c++) {
                        double w = b.weights[set][4 * v + c];
                        size_t j = (size_t)b.joints[set][4 * v + c];
                        if (w == 0 || j >= nj) continue;
                        sum += w;
                        if (slot[j] < 0) slot[j] = (int)boxes.size(), boxes.push_back({(int)j, EMPTY_BOX});
                        grow(boxes[slot[j]].box, q);
                    }
                if (p.skin < 0) {
                    if (slot[nj] < 0) slot[nj] = (int)boxes.size(), boxes.push_back({-1, EMPTY_BOX});
                    grow(boxes[slot[nj]].box, q);
                } else if (sum == 0) {
                    p.at_zero[k] = 1;
                }
            }
        }
    }
    m.bounds_ready = true;
}

// The moving draws' boxes at the pose motion_nodes made, from the bounds that follow the joints: each joint's box
// widened by the morph targets at their weights (each target's box of deltas, scaled: a sum of boxes) and carried
// by its matrix, joined over the draw's joints; relative to the scene's origin and a millionth wider, for the
// float rounding of the vertices the GPU writes.
// One placement's draws' boxes (jm: scratch for its joints' matrices).
void bound_place(const sb_motion &m, const sbm::MoPlace &p, sb_scene *s, std::vector<sb_m4> &jm) {
    const std::vector<double> &w = m.weights[p.node];
    sb_v3 elo = sb_v3_make(0, 0, 0), ehi = elo;
    for (size_t t = 0; t < p.tbox.size() && t < w.size(); t++) {
        if (w[t] == 0) continue;
        sb_v3 a = sb_v3_scale(p.tbox[t].lo, w[t]), b = sb_v3_scale(p.tbox[t].hi, w[t]);
        elo = sb_v3_add(elo, sb_v3_min(a, b)), ehi = sb_v3_add(ehi, sb_v3_max(a, b));
    }
    sb_m4 rigid = p.skin < 0 ? rigid_matrix(m, p) : sb_m4_identity();
    jm.resize(p.skin >= 0 ? m.skin_joints[p.skin].size() : 0);
    for (size_t j = 0; j < jm.size(); j++) jm[j] = joint_matrix(m, p, j);   // once a joint, not once a draw
    for (size_t k = 0; k < p.draws.size(); k++) {
        sb_aabb u = EMPTY_BOX;
        for (const sbm::JointBox &jb : p.dbox[k]) {
            sb_aabb b = {sb_v3_add(jb.box.lo, elo), sb_v3_add(jb.box.hi, ehi)};
            u = sb_aabb_union(u, sb_aabb_transform_affine(jb.joint < 0 ? rigid : jm[(size_t)jb.joint], &b));
        }
        if (p.at_zero[k]) grow(u, sb_v3_make(0, 0, 0));
        u.lo = sb_v3_sub(u.lo, s->origin), u.hi = sb_v3_sub(u.hi, s->origin);
        sb_v3 ext = sb_v3_sub(u.hi, u.lo), mag = sb_v3_max(sb_v3_abs(u.lo), sb_v3_abs(u.hi));
        double pad = 1e-6 * (sb_v3_len(ext) + sb_v3_len(mag)) + 1e-30;
        u.lo = sb_v3_sub(u.lo, sb_v3_make(pad, pad, pad)), u.hi = sb_v3_add(u.hi, sb_v3_make(pad, pad, pad));
        s->draws[p.draws[k]].box = u;
    }
}

// One placement at the pose motion_nodes made: its morph targets at its node's weights, then its skin or its
// node's transform, written into the scene.
// What one placement's posing writes as it goes (one a thread).
struct Scratch {
    std::vector<double> pos, nrm;
    std::vector<sb_m4> jm;
};

void motion_place(const sb_motion &m, Scratch &x, sb_scene *s, const sbm::MoPlace &p, bool boxes) {
    x.pos.assign(p.base.pos.begin(), p.base.pos.end());
    x.nrm.assign(p.base.nrm.begin(), p.base.nrm.end());
    const std::vector<double> &w = m.weights[p.node];
    for (size_t t = 0; t < p.dpos.size() && t < w.size(); t++) {
        if (w[t] == 0) continue;
        for (size_t i = 0; i < p.dpos[t].size() && i < x.pos.size(); i++) x.pos[i] += w[t] * p.dpos[t][i];
        for (size_t i = 0; i < p.dnrm[t].size() && i < x.nrm.size(); i++) x.nrm[i] += w[t] * p.dnrm[t][i];
    }
    if (p.skin >= 0) {
        x.jm.resize(m.skin_joints[p.skin].size());
        for (size_t j = 0; j < x.jm.size(); j++) x.jm[j] = joint_matrix(m, p, j);
        sbm::skin_vertices(x.jm, p.base, x.pos, x.nrm);
    } else {
        sb_m4 w4 = rigid_matrix(m, p), nm = sbm::normal_matrix(w4);
        for (size_t v = 0; v < x.pos.size() / 3; v++) {
            sb_v3 q = sb_m4_point(w4, sb_v3_make(x.pos[3 * v], x.pos[3 * v + 1], x.pos[3 * v + 2]));
            x.pos[3 * v] = q.x, x.pos[3 * v + 1] = q.y, x.pos[3 * v + 2] = q.z;
            if (!p.base.have_n) continue;
            sb_v3 nn = sb_m4_dir(nm, sb_v3_make(x.nrm[3 * v], x.nrm[3 * v + 1], x.nrm[3 * v + 2]));
            x.nrm[3 * v] = nn.x, x.nrm[3 * v + 1] = nn.y, x.nrm[3 * v + 2] = nn.z;
        }
    }
    sb_scene_repose_prim(s, p.first, p.count, x.pos.data(), p.base.have_n ? x.nrm.data() : nullptr, p.draws.data(),
                         (uint32_t)p.draws.size(), boxes);
}

// The placements are posed on the motion's threads (each writes vertices and boxes of its own): 64 skinned
// characters are 60 % of a frame on one core of this machine (docs/measurements.md, Moving casters).
// gpu_ones: the placements the GPU poses (their vertices only: their boxes follow the joints); else those it
// cannot pose (vertices and exact boxes).
uint32_t pose_places(sb_motion *m, sb_scene *s, bool gpu_ones) {
    std::vector<const sbm::MoPlace *> todo;
    for (const sbm::MoPlace &p : m->places)
        if (p.gpu == gpu_ones) todo.push_back(&p);
    size_t n = todo.size();
    std::atomic<size_t> next(0);
    in_parallel(*m, (unsigned)std::min<size_t>(n, 16), [&](unsigned) {
        Scratch x;
        for (size_t i; (i = next.fetch_add(1)) < n;) motion_place(*m, x, s, *todo[i], !gpu_ones);
    });
    return (uint32_t)n;
}

} // namespace

extern "C" uint32_t sb_motion_mark(sb_motion *m, sb_scene *s) {
    std::map<uint32_t, sbm::MoPlace *> place;   // a placement's first vertex -> it
    for (sbm::MoPlace &p : m->places) place[p.first] = &p, p.draws.clear();
    uint32_t n = 0;
    sb_aabb still = {{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
    for (uint32_t d = 0; d < s->draw_count; d++) {
        sb_draw &dr = s->draws[d];
        auto it = place.find(dr.first_vertex);
        dr.motion = it != place.end() ? it->second->kind : (uint8_t)SB_DRAW_STILL;
        if (it != place.end()) it->second->draws.push_back(d);   /* each pose writes these boxes, no search */
        n += dr.motion != SB_DRAW_STILL;
        if (dr.motion == SB_DRAW_STILL) still.lo = sb_v3_min(still.lo, dr.box.lo), still.hi = sb_v3_max(still.hi, dr.box.hi);
    }
    s->still_bounds = still;
    s->moving_draws = n;
    s->pose_time = NAN;
    return n;
}

extern "C" sb_motion_stats sb_motion_statistics(const sb_motion *m) {
    sb_motion_stats st;
    memset(&st, 0, sizeof st);
    st.clips = (uint32_t)m->clips.size();
    st.channels = (uint32_t)m->channels.size();
    st.skipped = m->skipped;
    st.animated_nodes = m->animated_nodes;
    st.pose_groups = (uint32_t)m->groups.size();
    st.lone_places = (uint32_t)m->lone_places.size();
    for (const sbm::MoPlace &p : m->places) {
        if (p.skin >= 0) st.skinned_prims++;
        else if (p.kind == SB_DRAW_DEFORMING) st.morphing_prims++;
        else st.rigid_prims++;
    }
    return st;
}

extern "C" sb_clip_info sb_motion_clip(const sb_motion *m, uint32_t i) {
    const sbm::MoClip &c = m->clips[i];
    return sb_clip_info{c.name.c_str(), c.duration, c.channels, c.nodes};
}

extern "C" void sb_motion_free(sb_motion *m) {
    if (m) delete m->workers;
    delete m;
}


extern "C" bool sb_scene_pose(sb_scene *s, double t) {
    if (!sb_scene_moves(s) || s->pose_time == t) return false;
    sb_motion *m = s->motion;
    motion_nodes(*m, t, s, s);   // and the boxes that follow the joints of the placements the GPU poses
    pose_places(m, s, false);   // the placements the GPU cannot pose: vertices and exact boxes, as ever
    s->pose_time = t;
    s->pose_serial++;
    sb_aabb b = s->still_bounds;
    for (uint32_t d = 0; d < s->draw_count; d++)
        if (s->draws[d].motion != SB_DRAW_STILL) {
            b.lo = sb_v3_min(b.lo, s->draws[d].box.lo);
            b.hi = sb_v3_max(b.hi, s->draws[d].box.hi);
        }
    s->bounds = b;
    sb_scene_refit_bvh(s);   /* the load's tree over the draws' boxes as they are now */
    return true;
}

extern "C" void sb_scene_sync_vertices(const sb_scene *s) {
    if (!sb_scene_moves(s) || s->motion->vertices_serial == s->pose_serial) return;
    sb_motion *m = s->motion;
    if (!(m->nodes_t == s->pose_time)) motion_nodes(*m, s->pose_time, s, nullptr);
    // the vertices are the CPU's copy of the pose the scene holds (its boxes stay sb_scene_pose's): writing them
    // changes nothing a const reader of the scene relies on but them
    uint32_t posed = pose_places(m, const_cast<sb_scene *>(s), true);
    m->vertices_serial = s->pose_serial;
    m->cpu_poses += posed > 0;
}

extern "C" uint64_t sb_scene_cpu_poses(const sb_scene *s) { return s->motion ? s->motion->cpu_poses : 0; }

extern "C" const sb_pose_data *sb_motion_gpu_data(const sb_scene *s) {
    if (!sb_scene_moves(s)) return nullptr;
    sb_motion &m = *s->motion;
    if (!m.bounds_ready) motion_bounds_prepare(m, s);
    if (!m.gpu.place_count) {
        m.gpu_places.clear(), m.gpu_rest.clear(), m.gpu_morph.clear(), m.gpu_draw.clear();
        uint32_t palette = 0, weights = 0, morph_rows = 0;
        for (const sbm::MoPlace &p : m.places) {
            if (!p.gpu || p.draws.empty()) continue;
            const sbm::RestData &b = p.base;
            sb_pose_place g = {};
            g.first = p.first, g.count = p.count;
            g.rest_first = (uint32_t)(m.gpu_rest.size() / SB_POSE_REST_FLOATS);
            g.palette_first = palette;
            g.joints = p.skin >= 0 ? (uint32_t)m.skin_joints[p.skin].size() : 0;
            palette += g.joints ? g.joints : 1;
            g.targets = (uint32_t)p.dpos.size();
            g.morph_first = morph_rows;
            g.weights_first = weights;
            weights += g.targets;
            morph_rows += g.targets * p.count;
            uint32_t id = (uint32_t)m.gpu_places.size();
            for (uint32_t v = 0; v < p.count; v++) {
                float row[SB_POSE_REST_FLOATS] = {0};
                for (int c = 0; c < 3; c++) row[c] = (float)b.pos[3 * v + c], row[4 + c] = (float)b.nrm[3 * v + c];
                memcpy(&row[3], &id, 4);
                for (int set = 0; set < (g.joints ? b.skin_sets : 0); set++)
                    for (int c = 0; c < 4; c++) {
                        uint32_t j = (uint32_t)b.joints[set][4 * v + c];
                        memcpy(&row[8 + 4 * set + c], &j, 4);
                        row[16 + 4 * set + c] = (float)b.weights[set][4 * v + c];
                    }
                m.gpu_rest.insert(m.gpu_rest.end(), row, row + SB_POSE_REST_FLOATS);
            }
            for (uint32_t t = 0; t < g.targets; t++)
                for (uint32_t v = 0; v < p.count; v++) {
                    float row[SB_POSE_MORPH_FLOATS] = {0};
                    for (int c = 0; c < 3; c++) {
                        size_t i = 3 * (size_t)v + c;
                        row[c] = i < p.dpos[t].size() ? (float)p.dpos[t][i] : 0;
                        row[4 + c] = t < p.dnrm.size() && i < p.dnrm[t].size() ? (float)p.dnrm[t][i] : 0;
                    }
                    m.gpu_morph.insert(m.gpu_morph.end(), row, row + SB_POSE_MORPH_FLOATS);
                }
            m.gpu_places.push_back(g);
            m.gpu_draw.push_back(p.draws[0]);
        }
        m.gpu.place_count = (uint32_t)m.gpu_places.size();
        m.gpu.rest_count = (uint32_t)(m.gpu_rest.size() / SB_POSE_REST_FLOATS);
        m.gpu.morph_count = morph_rows;
        m.gpu.palette_count = palette;
        m.gpu.weight_count = weights;
        m.gpu.places = m.gpu_places.data();
        m.gpu.place_draw = m.gpu_draw.data();
        m.gpu.rest = m.gpu_rest.data();
        m.gpu.morph = m.gpu_morph.data();
    }
    return m.gpu.place_count ? &m.gpu : nullptr;
}

extern "C" void sb_motion_gpu_frame(const sb_scene *s, float *palette, float *weights) {
    sb_motion &m = *s->motion;
    if (!(m.nodes_t == s->pose_time)) motion_nodes(m, s->pose_time, s, nullptr);
    size_t k = 0;
    for (const sbm::MoPlace &p : m.places) {
        if (!p.gpu || p.draws.empty()) continue;
        const sb_pose_place &g = m.gpu_places[k++];
        for (uint32_t j = 0; j < (g.joints ? g.joints : 1); j++) {
            sb_m4 a = g.joints ? joint_matrix(m, p, j) : rigid_matrix(m, p);
            a.m[12] -= s->origin.x, a.m[13] -= s->origin.y, a.m[14] -= s->origin.z;   // relative to the origin
            for (int e = 0; e < 16; e++) palette[16 * (size_t)(g.palette_first + j) + e] = (float)a.m[e];
        }
        const std::vector<double> &w = m.weights[p.node];
        for (uint32_t t = 0; t < g.targets; t++) weights[g.weights_first + t] = t < w.size() ? (float)w[t] : 0;
    }
}

extern "C" void sb_motion_info(const sb_scene *s, FILE *out) {
    if (s->motion) {
        sb_motion_stats m = sb_motion_statistics(s->motion);
        fprintf(out, "animation: %u clip(s) playing (--anim %s), %u channel(s) on %u node(s), %u left out; moving: %u of "
                "%u draws (%u rigid primitive placement(s), %u skinned, %u morphing)\n", m.clips,
                s->opts.anim == SB_ANIM_LIST ? s->opts.anim_clips : "all", m.channels, m.animated_nodes, m.skipped,
                s->moving_draws, s->draw_count, m.rigid_prims, m.skinned_prims, m.morphing_prims);
        for (uint32_t i = 0; i < m.clips; i++) {
            sb_clip_info c = sb_motion_clip(s->motion, i);
            if (c.channels)
                fprintf(out, "  clip %s: %.4g s (loops), %u channel(s), %u node(s)\n", c.name, c.duration, c.channels,
                        c.nodes);
            else
                fprintf(out, "  clip %s: nothing of its own (an earlier clip animates its nodes: --anim %s plays it)\n",
                        c.name, c.name);
        }
    } else {
        fprintf(out, "animation: %s\n", s->opts.pose ? "frozen at --pose" : s->opts.anim == SB_ANIM_NONE ?
                "none played (--anim none)" : "nothing moves");
    }
}

// ---- the scene cache's copy (motion.h: sb_motion_write, sb_motion_read) ----

namespace {

template <class T> void put_vec(sb_wbuf *b, const std::vector<T> &v) {
    sb_wbuf_put_u32(b, (uint32_t)v.size());
    sb_wbuf_put_array(b, v.data(), v.size() * sizeof(T));
}

template <class T> bool take_vec(sb_rbuf *r, std::vector<T> &v) {
    uint32_t n = sb_rbuf_take_u32(r);
    const T *p = (const T *)sb_rbuf_take_array(r, n, sizeof(T));
    if (!r->ok) return false;
    v.assign(p, p + (p ? n : 0));
    return true;
}

template <class T> void put_vecs(sb_wbuf *b, const std::vector<std::vector<T>> &v) {
    sb_wbuf_put_u32(b, (uint32_t)v.size());
    for (const auto &x : v) put_vec(b, x);
}

template <class T> bool take_vecs(sb_rbuf *r, std::vector<std::vector<T>> &v) {
    uint32_t n = sb_rbuf_take_u32(r);
    if (!r->ok || n > r->n - r->at) return r->ok = false;   // at least a length each
    v.resize(n);
    for (auto &x : v)
        if (!take_vec(r, x)) return false;
    return true;
}

void put_str(sb_wbuf *b, const std::string &s) {
    sb_wbuf_put_u32(b, (uint32_t)s.size());
    sb_wbuf_put(b, s.data(), s.size());
}

bool take_str(sb_rbuf *r, std::string &s) {
    uint32_t n = sb_rbuf_take_u32(r);
    const char *p = (const char *)sb_rbuf_take(r, n);
    if (!r->ok) return false;
    s.assign(p, n);
    return true;
}

void put_doubles(sb_wbuf *b, const sbm::Doubles &v) {
    sb_wbuf_put_u32(b, (uint32_t)v.size());
    sb_wbuf_put_array(b, v.data(), v.size() * sizeof(double));
}

// A view of the entry's array (aligned as written), for as long as the scene keeps the entry mapped.
bool take_doubles(sb_rbuf *r, sbm::Doubles &v) {
    uint32_t n = sb_rbuf_take_u32(r);
    const double *p = (const double *)sb_rbuf_take_array(r, n, sizeof(double));
    if (!r->ok) return false;
    v.view(p, p ? n : 0);
    return true;
}

void put_prim(sb_wbuf *b, const sbm::RestData &d) {   // what posing reads: not the texture coordinates nor the indices
    put_doubles(b, d.pos), put_doubles(b, d.nrm), put_vec(b, std::vector<double>()), put_vec(b, std::vector<uint32_t>());
    for (int k = 0; k < 2; k++) put_doubles(b, d.joints[k]), put_doubles(b, d.weights[k]);
    uint32_t flags[3] = {d.have_n, 0, (uint32_t)d.skin_sets};   // the second: have_uv once, unread
    sb_wbuf_put(b, flags, sizeof flags);
}

bool take_prim(sb_rbuf *r, sbm::RestData &d) {
    std::vector<double> uv;   // written empty
    std::vector<uint32_t> idx;
    bool ok = take_doubles(r, d.pos) && take_doubles(r, d.nrm) && take_vec(r, uv) && take_vec(r, idx);
    for (int k = 0; ok && k < 2; k++) ok = take_doubles(r, d.joints[k]) && take_doubles(r, d.weights[k]);
    const uint32_t *f = ok ? (const uint32_t *)sb_rbuf_take(r, 3 * sizeof(uint32_t)) : nullptr;
    if (!f) return r->ok = false;
    uint32_t flags[3];
    memcpy(flags, f, sizeof flags);
    d.have_n = flags[0] != 0, d.skin_sets = (int)flags[2];
    return d.skin_sets <= 2 && d.pos.size() % 3 == 0 && (!d.have_n || d.nrm.size() == d.pos.size());
}

} // namespace

extern "C" void sb_motion_write(const sb_motion *m, sb_wbuf *b) {
    put_vec(b, m->parent), put_vec(b, m->topo), put_vec(b, m->rest), put_vec(b, m->has_matrix);
    put_vec(b, m->rest_local), put_vecs(b, m->rest_weights);
    sb_wbuf_put_u32(b, (uint32_t)m->channels.size());
    for (const sbm::MoChannel &c : m->channels) {
        int32_t head[6] = {c.clip, c.node, c.path, c.ch.s.ncomp, c.ch.s.rotation, (int32_t)c.ch.s.interp};
        sb_wbuf_put(b, head, sizeof head);
        put_vec(b, c.ch.in), put_vec(b, c.ch.out);
    }
    sb_wbuf_put_u32(b, (uint32_t)m->clips.size());
    for (const sbm::MoClip &c : m->clips) {
        put_str(b, c.name);
        sb_wbuf_put(b, &c.duration, sizeof c.duration);
        uint32_t counts[2] = {c.channels, c.nodes};
        sb_wbuf_put(b, counts, sizeof counts);
    }
    sb_wbuf_put_u32(b, (uint32_t)m->places.size());
    for (const sbm::MoPlace &p : m->places) {
        int32_t head[5] = {p.node, p.skin, (int32_t)p.first, (int32_t)p.count, p.kind};
        sb_wbuf_put(b, head, sizeof head);
        sb_wbuf_put(b, &p.inst, sizeof p.inst);
        put_prim(b, p.base), put_vecs(b, p.dpos), put_vecs(b, p.dnrm);
    }
    put_vecs(b, m->skin_joints), put_vecs(b, m->skin_ibm);
    uint32_t counts[2] = {m->skipped, m->animated_nodes};
    sb_wbuf_put(b, counts, sizeof counts);
}

extern "C" sb_motion *sb_motion_read(sb_rbuf *r, const sb_scene *s) {
    std::unique_ptr<sb_motion> m(new sb_motion);
    bool ok = take_vec(r, m->parent) && take_vec(r, m->topo) && take_vec(r, m->rest) && take_vec(r, m->has_matrix) &&
              take_vec(r, m->rest_local) && take_vecs(r, m->rest_weights);
    size_t nn = m->parent.size();
    ok = ok && m->topo.size() == nn && m->rest.size() == nn && m->has_matrix.size() == nn &&
         m->rest_local.size() == nn && m->rest_weights.size() == nn;
    for (int p : m->parent) ok = ok && p >= -1 && p < (int)nn;
    for (int t : m->topo) ok = ok && t >= 0 && t < (int)nn;
    uint32_t nc = ok ? sb_rbuf_take_u32(r) : 0;
    for (uint32_t i = 0; ok && r->ok && i < nc; i++) {
        const int32_t *h = (const int32_t *)sb_rbuf_take(r, 6 * sizeof(int32_t));
        if (!h) return nullptr;
        int32_t head[6];
        memcpy(head, h, sizeof head);
        sbm::MoChannel c{head[0], head[1], head[2], {}};
        ok = take_vec(r, c.ch.in) && take_vec(r, c.ch.out) && head[1] >= 0 && head[1] < (int)nn && head[0] >= 0 &&
             head[3] > 0 && head[3] <= 64 && head[5] >= 0 && head[5] <= SB_INTERP_CUBIC && !c.ch.in.empty() &&
             c.ch.out.size() == (head[5] == SB_INTERP_CUBIC ? 3 : 1) * c.ch.in.size() * (size_t)head[3];
        if (!ok) break;
        m->channels.push_back(std::move(c));
        sbm::MoChannel &mc = m->channels.back();   // the sampler reads its own arrays
        mc.ch.s = {mc.ch.in.data(), mc.ch.out.data(), mc.ch.in.size(), head[3], head[4] != 0, (sb_interp)head[5]};
    }
    uint32_t nclips = ok && r->ok ? sb_rbuf_take_u32(r) : 0;
    for (uint32_t i = 0; ok && r->ok && i < nclips; i++) {
        sbm::MoClip c;
        const void *d = take_str(r, c.name) ? sb_rbuf_take(r, sizeof c.duration) : nullptr;
        const void *k = d ? sb_rbuf_take(r, 2 * sizeof(uint32_t)) : nullptr;
        if (!k) return nullptr;
        memcpy(&c.duration, d, sizeof c.duration);
        uint32_t counts[2];
        memcpy(counts, k, sizeof counts);
        c.channels = counts[0], c.nodes = counts[1];
        m->clips.push_back(std::move(c));
    }
    for (const sbm::MoChannel &c : m->channels) ok = ok && c.clip < (int)m->clips.size();
    uint32_t np = ok && r->ok ? sb_rbuf_take_u32(r) : 0;
    for (uint32_t i = 0; ok && r->ok && i < np; i++) {
        const int32_t *h = (const int32_t *)sb_rbuf_take(r, 5 * sizeof(int32_t));
        const void *inst = h ? sb_rbuf_take(r, sizeof(sb_m4)) : nullptr;
        if (!inst) return nullptr;
        int32_t head[5];
        memcpy(head, h, sizeof head);
        sbm::MoPlace p;
        p.node = head[0], p.skin = head[1], p.first = (uint32_t)head[2], p.count = (uint32_t)head[3];
        p.kind = (uint8_t)head[4];
        memcpy(&p.inst, inst, sizeof p.inst);
        ok = take_prim(r, p.base) && take_vecs(r, p.dpos) && take_vecs(r, p.dnrm) && p.node >= 0 && p.node < (int)nn &&
             (uint64_t)p.first + p.count <= s->vertex_count && p.base.pos.size() == 3 * (size_t)p.count;
        if (ok) m->places.push_back(std::move(p));
    }
    ok = ok && r->ok && take_vecs(r, m->skin_joints) && take_vecs(r, m->skin_ibm) &&
         m->skin_joints.size() == m->skin_ibm.size();
    for (size_t k = 0; ok && k < m->skin_joints.size(); k++) {
        ok = m->skin_joints[k].size() == m->skin_ibm[k].size();
        for (int j : m->skin_joints[k]) ok = ok && j >= 0 && j < (int)nn;
    }
    for (const sbm::MoPlace &p : m->places) ok = ok && p.skin >= -1 && p.skin < (int)m->skin_joints.size();
    const uint32_t *c = ok ? (const uint32_t *)sb_rbuf_take(r, 2 * sizeof(uint32_t)) : nullptr;
    if (!c || !r->ok) return nullptr;
    uint32_t counts[2];
    memcpy(counts, c, sizeof counts);
    m->skipped = counts[0], m->animated_nodes = counts[1];
    return m.release();
}
