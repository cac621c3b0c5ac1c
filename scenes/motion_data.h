/* motion_data.h - what the glTF adapter (gltf_load.cc) and the motion module
 * (motion.cc) share, C++ only: a primitive's vertex data as read, an animation
 * channel as a sampler, and the played clips (struct sb_motion, motion.h's
 * opaque type) with every moving placement and the data to pose it again. */
#pragma once
#ifndef __cplusplus
#error "motion_data.h is C++ (gltf_load.cc and motion.cc)"
#endif
#include <cmath>
#include <string>
#include <vector>

extern "C" {
#include "anim.h"
#include "pose_data.h"
#include "scene.h"
}

namespace sbm {

// One animation channel read into a sampler (its arrays kept alive by the owner).
struct Channel {
    std::vector<double> in, out;
    sb_anim_sampler s;
};

// A primitive's vertex data, from accessors or a Draco bitstream.
struct PrimData {
    std::vector<double> pos, nrm, uv;
    std::vector<uint32_t> idx;          // as the file lists them (mode 4, 5 or 6)
    std::vector<double> joints[2], weights[2];
    bool have_n = false, have_uv = false;
    int skin_sets = 0;
};

// The inverse transpose of the upper 3x3: what transforms normals.
inline sb_m4 normal_matrix(const sb_m4 &w) {
    sb_m4 nm = sb_m4_identity(), inv;
    if (sb_m4_invert(w, &inv))
        for (int r = 0; r < 3; r++)
            for (int col = 0; col < 3; col++) nm.m[col * 4 + r] = inv.m[r * 4 + col];
    return nm;
}

// An array of doubles a moving placement's rest data holds: its own (a file read), or a view of the scene cache's
// entry, which stays mapped as long as the scene (a cached load copies none of it).
class Doubles {
  public:
    Doubles() = default;
    Doubles(const std::vector<double> &v) : own_(v) {}
    void view(const double *p, size_t n) { own_.clear(), view_ = p, n_ = n; }
    const double *data() const { return view_ ? view_ : own_.data(); }
    size_t size() const { return view_ ? n_ : own_.size(); }
    bool empty() const { return size() == 0; }
    const double &operator[](size_t i) const { return data()[i]; }
    const double *begin() const { return data(); }
    const double *end() const { return data() + size(); }

  private:
    std::vector<double> own_;
    const double *view_ = nullptr;
    size_t n_ = 0;
};

// What posing reads of a primitive's vertex data: positions, normals and skin (not the texture coordinates or
// the indices).
struct RestData {
    Doubles pos, nrm, joints[2], weights[2];
    bool have_n = false;
    int skin_sets = 0;
    RestData() = default;
    RestData(const PrimData &d)
        : pos(d.pos), nrm(d.nrm), joints{d.joints[0], d.joints[1]}, weights{d.weights[0], d.weights[1]},
          have_n(d.have_n), skin_sets(d.skin_sets) {}
};

// The skinned positions and normals of a primitive's vertices: each by its joints' matrices (world x inverse
// bind), weighted. The joints were checked against the skin where the primitive was first read. D: PrimData
// (at load) or RestData (posing again).
template <class D>
inline void skin_vertices(const std::vector<sb_m4> &jm, const D &d, std::vector<double> &pos, std::vector<double> &nrm) {
    size_t nv = pos.size() / 3;
    for (size_t v = 0; v < nv; v++) {
        sb_m4 sum = {{0}};
        for (int set = 0; set < d.skin_sets; set++)
            for (int k = 0; k < 4; k++) {
                double wgt = d.weights[set][4 * v + k];
                size_t j = (size_t)d.joints[set][4 * v + k];
                if (wgt == 0 || j >= jm.size()) continue;
                for (int e = 0; e < 16; e++) sum.m[e] += wgt * jm[j].m[e];
            }
        sb_v3 q = sb_m4_point(sum, sb_v3_make(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]));
        pos[3 * v] = q.x, pos[3 * v + 1] = q.y, pos[3 * v + 2] = q.z;
        if (!d.have_n) continue;
        sb_v3 n = sb_m4_dir(normal_matrix(sum), sb_v3_make(nrm[3 * v], nrm[3 * v + 1], nrm[3 * v + 2]));
        nrm[3 * v] = n.x, nrm[3 * v + 1] = n.y, nrm[3 * v + 2] = n.z;
    }
}

enum { PATH_T, PATH_R, PATH_S, PATH_W };   // what a channel animates: translation, rotation, scale, weights

struct MoChannel {
    int clip, node, path;
    Channel ch;
};

struct MoClip {
    std::string name;
    double duration = 0;
    uint32_t channels = 0, nodes = 0;
};

// The box, in the mesh's own space, of the vertices of one draw a joint moves (joint -1: a rigid placement's).
struct JointBox {
    int joint;
    sb_aabb box;
};

// A primitive placement that moves: what posing it again needs.
struct MoPlace {
    int node = -1, skin = -1;                       // skin: its joints pose it (the node's transform is ignored)
    sb_m4 inst = sb_m4_identity();                  // an EXT_mesh_gpu_instancing instance, relative to the node
    RestData base;                                  // object space, before morph targets and skin
    std::vector<std::vector<double>> dpos, dnrm;    // the morph targets' deltas (empty: none)
    uint32_t first = 0, count = 0;                  // its vertices in the scene
    std::vector<uint32_t> draws;                    // its draws once the scene is finished (sb_motion_mark)
    uint8_t kind = SB_DRAW_RIGID;
    // bounds that follow the joints (motion.cc, motion_bounds): made at the first pose, never cached
    bool gpu = false;                               // the GPU poses it (normals in the file, no negative weight)
    std::vector<std::vector<JointBox>> dbox;        // per draw: each joint's share of its vertices (rigid: one)
    std::vector<char> at_zero;                      // per draw: a vertex no joint weighs (posed at the world's 0)
    std::vector<sb_aabb> tbox;                      // per morph target: the box of its position deltas
};

class Workers;   // motion.cc: the threads a pose's groups share

} // namespace sbm

// The clips that play (motion.h): the node graph's rest pose, the channels, the moving placements.
struct sb_motion {
    std::vector<int> parent, topo;                  // topo: every node after its parent
    std::vector<sb_trs> rest;
    std::vector<char> has_matrix;
    std::vector<sb_m4> rest_local;
    std::vector<std::vector<double>> rest_weights;
    std::vector<sbm::MoChannel> channels;
    std::vector<sbm::MoClip> clips;
    std::vector<sbm::MoPlace> places;
    std::vector<std::vector<int>> skin_joints;
    std::vector<std::vector<sb_m4>> skin_ibm;
    uint32_t skipped = 0, animated_nodes = 0;
    // the nodes at the pose (motion_nodes), read by every placement's posing
    std::vector<sb_trs> trs;
    std::vector<char> anim, moving;                 // a channel moves it; it or a node above it is moved
    std::vector<sb_m4> world;
    std::vector<std::vector<double>> weights;
    double nodes_t = NAN;                           // the clip time world and weights hold (NAN: none yet)
    bool bounds_ready = false;                      // every placement's dbox made (motion_bounds_prepare)
    // the pose's work in groups that share no node (motion.cc, motion_prepare_groups), and the threads it runs on
    struct Group {
        std::vector<uint32_t> channels, places;
        std::vector<int> nodes;                     // in topological order
    };
    std::vector<Group> groups;
    std::vector<uint32_t> lone_channels, lone_places;
    bool groups_ready = false;
    sbm::Workers *workers = nullptr;                // sb_motion_free ends them
    // the scene's vertices on the CPU (sb_scene_sync_vertices): the pose serial they hold, and how often posed
    uint64_t vertices_serial = 0;
    uint64_t cpu_poses = 0;
    sb_pose_data gpu = {};                          // what the GPU's posing pass reads (sb_motion_gpu_data)
    std::vector<sb_pose_place> gpu_places;
    std::vector<float> gpu_rest, gpu_morph;
    std::vector<uint32_t> gpu_draw;
};
