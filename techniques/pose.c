/* pose.c - the GPU's posing pass: a moving scene's skinned, morphing and rigid placements posed by a compute
 * pass (shaders/pose.comp) into the scene's vertex buffer, from rest data sent once (scenes/motion.h,
 * sb_pose_data) and, each pose, the joints' matrices and the morph weights. The CPU poses its own copy of the
 * vertices only where something reads it (sb_scene_sync_vertices). Placements the GPU cannot pose (the CPU's
 * face normals, a negative skin weight) are posed on the CPU by sb_scene_pose and sent as before; so is every
 * placement where this GL's storage blocks cannot hold the rest data. */
#include "pose.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "motion.h"
#include "shaders.h"
#include "util.h"

const sb_stage_def sb_stage_pose = {
    .name = "pose",
    .doc = "the posing pass: a moving scene's skinned, morphing and rigid vertices posed by the GPU once a pose, in "
           "the first frame drawn at it (empty: nothing moves, or the CPU poses every placement)"};

#define POSE_GROUP 64        /* pose.comp's local size */
#define POSE_MAX_GROUPS 65535u

typedef struct pose_chunk {
    uint32_t rest0, rows;         /* its placements' rest rows */
    GLintptr vtx_off;             /* the bound range of the vertex buffer, aligned */
    GLsizeiptr vtx_len;
} pose_chunk;

typedef struct sb_gpu_pose {
    const sb_pose_data *data;
    GLuint prog, places, rest, morph, palette, weights;
    GLint u_rows, u_row0, u_rest_base, u_vertex_base, u_origin;
    GLint align;                  /* the storage buffers' offset alignment */
    uint32_t rows_aligned;        /* rest rows a whole number of it */
    float *palette_cpu, *weights_cpu;
    sb_pose_place *places_gpu;    /* the places with the vertex buffer's numbering */
    pose_chunk *chunks;
    uint32_t chunk_count;
    GLint64 block;                /* the largest storage block a dispatch binds (block_bytes, at init) */
    uint32_t dispatch_rows;       /* rest rows a dispatch poses at most */
    uint32_t dispatches;          /* the last pose's (a test reads it: sb_gpu_pose_dispatches) */
    uint8_t *cpu_draw;            /* per draw: a moving draw the CPU poses (sent from the scene's vertices) */
    const uint32_t *vbase;        /* per draw: its first vertex in the vertex buffer (the owner's, kept current) */
    bool mapped;                  /* places_gpu and chunks hold the vertex buffer's numbering as uploaded */
    bool pending;                 /* a pose not yet run (sb_gpu_update_motion) */
} sb_gpu_pose;

/* The largest storage block a dispatch binds: the GL's, or less where SB_POSE_BLOCK_BYTES says (a test seam: the
 * chunked dispatches a GPU with small blocks takes, on a scene of a character). */
static GLint64 block_bytes(void) {
    GLint64 block = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &block);
    const char *cap = getenv("SB_POSE_BLOCK_BYTES");
    long long c = cap ? atoll(cap) : 0;
    return c > 0 && c < block ? (GLint64)c : block;
}

static GLuint storage(const void *data, size_t bytes) {
    GLuint b;
    glGenBuffers(1, &b);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, b);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(bytes ? bytes : 16), data, data ? GL_STATIC_DRAW : GL_DYNAMIC_DRAW);
    return b;
}

bool sb_pose_create(sb_gpu_pose **out, const sb_scene *s, const uint32_t *vbase, sb_err *err) {
    *out = NULL;
    const sb_pose_data *d = sb_motion_gpu_data(s);
    if (!d) return true;
    GLint64 block = block_bytes();
    size_t morph_bytes = (size_t)d->morph_count * SB_POSE_MORPH_FLOATS * 4, palette_bytes = (size_t)d->palette_count * 64,
           largest = 0;
    for (uint32_t i = 0; i < d->place_count; i++) {
        size_t b = (size_t)d->places[i].count * SB_VERTEX_BYTES + 4096;   /* its vertices, an aligned range */
        largest = b > largest ? b : largest;
    }
    if ((GLint64)morph_bytes > block || (GLint64)palette_bytes > block || (GLint64)largest > block ||
        (GLint64)((size_t)d->place_count * sizeof(sb_pose_place)) > block) {
        sb_log("%s: the posing data (%.0f MB of morph targets, %.0f MB of matrices) pass this GL's storage blocks "
               "(%.0f MB): the CPU poses every placement and sends its vertices", s->file, morph_bytes / 1e6,
               palette_bytes / 1e6, block / 1e6);
        return true;
    }
    const char *cs[] = {sb_shader_pose_comp};
    const sb_shader_src st[] = {{GL_COMPUTE_SHADER, cs, 1}};
    GLuint prog = sb_gpu_link("pose", "", st, 1, err);
    if (!prog) return false;
    sb_gpu_pose *p = sb_xcalloc(1, sizeof *p);
    p->data = d;
    p->vbase = vbase;
    p->prog = prog;
    p->block = block;
    p->u_rows = glGetUniformLocation(prog, "u_rows");
    p->u_row0 = glGetUniformLocation(prog, "u_row0");
    p->u_rest_base = glGetUniformLocation(prog, "u_rest_base");
    p->u_vertex_base = glGetUniformLocation(prog, "u_vertex_base");
    p->u_origin = glGetUniformLocation(prog, "u_origin");
    glGetIntegerv(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT, &p->align);
    if (p->align < 4) p->align = 4;
    p->rows_aligned = 1;
    while ((p->rows_aligned * SB_POSE_REST_FLOATS * 4) % (uint32_t)p->align) p->rows_aligned++;
    p->places_gpu = sb_xmalloc(sizeof(sb_pose_place) * d->place_count);
    p->places = storage(NULL, sizeof(sb_pose_place) * d->place_count);
    p->rest = storage(d->rest, (size_t)d->rest_count * SB_POSE_REST_FLOATS * 4);
    p->morph = storage(d->morph, morph_bytes);
    p->palette = storage(NULL, palette_bytes);
    p->weights = storage(NULL, (size_t)d->weight_count * 4);
    p->palette_cpu = sb_xmalloc(palette_bytes ? palette_bytes : 4);
    p->weights_cpu = sb_xmalloc(d->weight_count ? d->weight_count * 4 : 4);
    p->chunks = sb_xmalloc(sizeof(pose_chunk) * d->place_count);
    /* the moving draws the GPU leaves to the CPU: those of no placement it poses */
    p->cpu_draw = sb_xcalloc(s->draw_count + 1, 1);
    uint8_t *gpu_vertex = sb_xcalloc(s->vertex_count + 1, 1);
    for (uint32_t i = 0; i < d->place_count; i++) gpu_vertex[d->places[i].first] = 1;
    for (uint32_t k = 0; k < s->draw_count; k++)
        p->cpu_draw[k] = s->draws[k].motion != SB_DRAW_STILL && !gpu_vertex[s->draws[k].first_vertex];
    free(gpu_vertex);
    *out = p;
    return true;
}

/* The vertex buffer's numbering as uploaded now (sb_gpu_share may upload it again), and the dispatches: runs of
 * placements whose rest rows and vertex range each fit a storage block. */
static void pose_map(sb_gpu_pose *p, const sb_scene *s) {
    const sb_pose_data *d = p->data;
    const GLint align = p->align;
    /* room for aligned starts */
    const GLint64 block = p->block - align - (GLint64)p->rows_aligned * SB_POSE_REST_FLOATS * 4;
    for (uint32_t i = 0; i < d->place_count; i++) {
        p->places_gpu[i] = d->places[i];
        uint32_t dr = d->place_draw[i];
        p->places_gpu[i].first = p->vbase[dr] + (d->places[i].first - s->draws[dr].first_vertex);
    }
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, p->places);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(sizeof(sb_pose_place) * d->place_count), p->places_gpu);
    p->chunk_count = 0;
    for (uint32_t i = 0; i < d->place_count;) {
        pose_chunk c = {.rest0 = d->places[i].rest_first};
        uint64_t lo = UINT64_MAX, hi = 0;
        uint32_t j = i;
        for (; j < d->place_count; j++) {
            const sb_pose_place *q = &p->places_gpu[j];
            uint64_t nlo = lo < (uint64_t)q->first * SB_VERTEX_BYTES ? lo : (uint64_t)q->first * SB_VERTEX_BYTES;
            uint64_t nhi = hi > (uint64_t)(q->first + q->count) * SB_VERTEX_BYTES ? hi
                                                                                  : (uint64_t)(q->first + q->count) * SB_VERTEX_BYTES;
            nlo -= nlo % (uint64_t)align;
            if (j > i && (int64_t)(nhi - nlo) > block) break;
            lo = nlo, hi = nhi, c.rows = q->rest_first + q->count - c.rest0;
        }
        c.vtx_off = (GLintptr)lo;
        c.vtx_len = (GLsizeiptr)(hi - lo);
        p->chunks[p->chunk_count++] = c;
        i = j;
    }
    /* each dispatch's rest rows: a block's worth at most (its range starts aligned), and the groups one allows */
    uint64_t fit = (uint64_t)block / (SB_POSE_REST_FLOATS * 4);
    p->dispatch_rows = (uint32_t)(fit < (uint64_t)POSE_MAX_GROUPS * POSE_GROUP ? fit : (uint64_t)POSE_MAX_GROUPS * POSE_GROUP);
    p->mapped = true;
}

void sb_pose_remap(sb_gpu_pose *p) {
    if (p) p->mapped = false, p->pending = true;
}

void sb_pose_due(sb_gpu_pose *p) {
    if (p) p->pending = true;
}

bool sb_pose_pending(const sb_gpu_pose *p, const sb_scene *s) { return p && p->pending && !isnan(s->pose_time); }

bool sb_pose_run(sb_gpu_pose *p, const sb_scene *s, GLuint vbo) {
    if (!sb_pose_pending(p, s)) return false;
    p->pending = false;
    const sb_pose_data *d = p->data;
    if (!p->mapped) pose_map(p, s);
    sb_motion_gpu_frame(s, p->palette_cpu, p->weights_cpu);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, p->palette);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)d->palette_count * 64, p->palette_cpu);
    if (d->weight_count) {
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, p->weights);
        glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)d->weight_count * 4, p->weights_cpu);
    }
    p->dispatches = 0;
    glUseProgram(p->prog);
    glUniform3f(p->u_origin, (float)s->origin.x, (float)s->origin.y, (float)s->origin.z);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 8, p->places);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 10, p->morph);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 11, p->palette);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 12, p->weights);
    for (uint32_t k = 0; k < p->chunk_count; k++) {
        const pose_chunk *c = &p->chunks[k];
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 13, vbo, c->vtx_off, c->vtx_len);
        glUniform1ui(p->u_vertex_base, (GLuint)(c->vtx_off / 4));
        for (uint32_t done = 0; done < c->rows;) {
            uint32_t rows = c->rows - done;
            if (rows > p->dispatch_rows) rows = p->dispatch_rows;
            uint32_t r0 = c->rest0 + done, rb = r0 - r0 % p->rows_aligned;   /* the bound range starts aligned */
            glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 9, p->rest, (GLintptr)rb * SB_POSE_REST_FLOATS * 4,
                              (GLsizeiptr)(r0 + rows - rb) * SB_POSE_REST_FLOATS * 4);
            glUniform1ui(p->u_rest_base, rb);
            glUniform1ui(p->u_row0, r0 - rb);
            glUniform1ui(p->u_rows, r0 + rows - rb);
            glDispatchCompute((rows + POSE_GROUP - 1) / POSE_GROUP, 1, 1);
            p->dispatches++;
            done += rows;
        }
    }
    glMemoryBarrier(GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    glUseProgram(0);
    return true;
}

void sb_pose_dispatches(const sb_gpu_pose *p, uint32_t *chunks, uint32_t *dispatches) {
    *chunks = p ? p->chunk_count : 0;
    *dispatches = p ? p->dispatches : 0;
}

bool sb_pose_leaves(const sb_gpu_pose *p, uint32_t d) { return !p || p->cpu_draw[d]; }

void sb_pose_free(sb_gpu_pose *p) {
    if (!p) return;
    glDeleteProgram(p->prog);
    GLuint bufs[] = {p->places, p->rest, p->morph, p->palette, p->weights};
    glDeleteBuffers(5, bufs);
    free(p->palette_cpu);
    free(p->weights_cpu);
    free(p->places_gpu);
    free(p->chunks);
    free(p->cpu_draw);
    free(p);
}
