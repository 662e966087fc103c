/*
 * embree_shim.h - a small, version-neutral C API over Embree 3 or Embree 4.
 *
 * Rust binds this header (bindgen, allowlisted to the vo_ names) instead of Embree's own, so
 * that the Rust side never sees the API differences between Embree 3 (RTCIntersectContext,
 * ray streams) and Embree 4 (RTCIntersectArguments, no streams), and never has to re-implement
 * Embree's inline helpers (rtcInitIntersectContext, rtcInterpolate0/1), which have no exported
 * symbol. The shim is compiled against whichever major version build.rs found; the choice is
 * made on RTC_VERSION_MAJOR in embree_shim.c.
 *
 * Handles are opaque pointers. Buffers passed to vo_geometry_triangles are shared, not copied:
 * the caller keeps them alive, unmodified, until the scene is released, and pads them so that
 * Embree's 16-byte loads past the last element stay inside the allocation.
 */
#ifndef VASTOCEAN_EMBREE_SHIM_H
#define VASTOCEAN_EMBREE_SHIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* primitive index of a ray that hit nothing */
#define VO_INVALID_ID 0xFFFFFFFFu

/* Scene build quality, mapped onto RTCBuildQuality. */
typedef enum vo_quality { VO_QUALITY_LOW = 0, VO_QUALITY_MEDIUM = 1, VO_QUALITY_HIGH = 2, VO_QUALITY_REFIT = 3 } vo_quality;

/* Scene flags (bit set), mapped onto RTCSceneFlags. */
#define VO_SCENE_COMPACT 1u
#define VO_SCENE_ROBUST 2u

/* Called by Embree on every device error; `user` is the pointer given at device creation. */
typedef void (*vo_error_fn)(void *user, int code, const char *message);

/* A ray, laid out for easy filling from Rust: origin, tnear, direction, tfar. */
typedef struct vo_ray {
  float org[3];
  float tnear;
  float dir[3];
  float tfar;
} vo_ray;

/* The closest hit of a ray: prim == VO_INVALID_ID when it missed. (u, v) are Embree's
 * barycentrics: the hit point is (1-u-v)*v0 + u*v1 + v*v2. ng is the unnormalized geometric
 * normal (v1-v0) x (v2-v0) as Embree reports it (in the instance's own space for an instance's
 * hit). inst is the id of the instance geometry the hit lies in, VO_INVALID_ID for a hit on a
 * geometry of the traced scene itself. */
typedef struct vo_hit {
  float t;
  float u;
  float v;
  uint32_t prim;
  uint32_t geom;
  uint32_t inst;
  float ng[3];
} vo_hit;

typedef struct vo_version {
  int major;
  int minor;
  int patch;
} vo_version;

/* The Embree version this shim was compiled against (from the headers). */
vo_version vo_compiled_version(void);

/* Creates a device from an Embree config string (e.g. "threads=2"); NULL on failure. */
void *vo_device_new(const char *config, vo_error_fn on_error, void *user);
void vo_device_release(void *device);
/* The last error code of the device (RTCError), clearing it; 0 means none. */
int vo_device_take_error(void *device);
/* The version the loaded library reports at run time. */
vo_version vo_device_version(void *device);
/* Creates a device with verbose=1 and copies Embree's banner (CPU, ISA, threads, tasking)
 * into buf (NUL-terminated, truncated to len). Returns the number of bytes written. */
size_t vo_describe(const char *config, char *buf, size_t len);

/* Bytes Embree holds for this device now, and the most it has held since it was created
 * (from its memory monitor callback). */
void vo_device_memory(void *device, long long *bytes, long long *peak);

/* Sets flush-to-zero and denormals-are-zero in this thread's MXCSR, as Embree asks of every
 * thread that traces (denormal arithmetic is many times slower in its kernels). */
void vo_flush_denormals(void);

/* Scenes */
void *vo_scene_new(void *device, vo_quality quality, uint32_t flags);
void vo_scene_release(void *scene);
/* Attaches a triangle mesh from caller-owned buffers and commits the geometry.
 * positions: 3 floats per vertex (12-byte stride) with at least 4 readable bytes after the
 * last vertex; indices: 3 uint32 per triangle; uvs: 2 floats per vertex with at least 8
 * readable bytes after the last one, or NULL for none (stored in vertex-attribute slot 0).
 * Returns the geometry handle (owned by the scene) or NULL on error; *geom_id receives its id. */
void *vo_scene_attach_triangles(void *device, void *scene, vo_quality quality, const float *positions,
                                size_t vertex_count, const uint32_t *indices, size_t triangle_count,
                                const float *uvs, uint32_t *geom_id);
/* One grid of a grid geometry (Embree's RTCGrid): width x height vertices, the first at
 * `start`, each row `stride` vertices after the one before. */
typedef struct vo_grid {
  uint32_t start;
  uint32_t stride;
  uint16_t width;
  uint16_t height;
} vo_grid;
/* Attaches a grid geometry (RTC_GEOMETRY_TYPE_GRID) over caller-owned vertices (shared, as for
 * triangles; the grids are copied) and commits it. A hit on it reports the grid as prim and
 * (u, v) from 0 to 1 across the whole grid (u along a row, v down the rows); each quad is split
 * into the triangles (v0, v1, v3) and (v2, v3, v1), v0 its first row's first vertex, v1 the
 * next, v2 and v3 the vertices below them. Returns the geometry handle (owned by the scene) or
 * NULL on error; *geom_id receives its id. */
void *vo_scene_attach_grids(void *device, void *scene, vo_quality quality, const float *positions,
                            size_t vertex_count, const vo_grid *grids, size_t grid_count, uint32_t *geom_id);
/* Attaches an instance of the committed scene `child` (which must outlive `scene`), placed by
 * the affine transform xfm (3x4, column-major: the three columns of the linear part, then the
 * translation; from the child's space into the scene's), and commits the geometry. Returns the
 * geometry handle (owned by the scene) or NULL on error; *geom_id receives its id, which hits
 * inside it report as their inst. */
void *vo_scene_attach_instance(void *device, void *scene, void *child, const float xfm[12], uint32_t *geom_id);
void vo_scene_commit(void *scene);
/* After the caller changed the vertex buffer in place: tells Embree, commits the geometry (and
 * `second`, another geometry over the same vertices, unless NULL) and the scene. With the
 * geometry attached at VO_QUALITY_REFIT, Embree refits the BVH's bounds instead of rebuilding
 * it. */
void vo_scene_refit(void *scene, void *geometry, void *second);
void vo_scene_bounds(void *scene, float lower[3], float upper[3]);

/* User geometry: primitives the caller bounds and intersects itself (the exact ocean surface's
 * prisms). `bounds` writes primitive prim's box; `intersect` tests primitive prim against the
 * ray for a hit with t in [ray->tnear, ray->tfar] and on a hit writes *t, *u, *v and returns 1.
 * `query` is the pointer handed to vo_intersect1_query for this ray (NULL from the other
 * queries): per-ray state the caller keeps across the primitives one ray meets. Both are
 * called from the threads that build and trace, at once. */
typedef void (*vo_bounds_fn)(void *user, uint32_t prim, float lower[3], float upper[3]);
typedef int (*vo_intersect_fn)(void *user, void *query, uint32_t prim, const vo_ray *ray, float *t,
                               float *u, float *v);

typedef struct vo_user_geometry {
  vo_bounds_fn bounds;
  vo_intersect_fn intersect;
  void *user;
} vo_user_geometry;

/* Attaches prim_count user primitives and commits the geometry; `callbacks` (and what its user
 * pointer points to) must outlive the scene. Hits report the primitive's id, the caller's
 * (u, v) and a geometric normal of (0, 1, 0). Returns the geometry handle (owned by the scene)
 * or NULL on error. */
void *vo_scene_attach_user(void *device, void *scene, vo_quality quality, size_t prim_count,
                           const vo_user_geometry *callbacks, uint32_t *geom_id);

/* Queries; the scene must be committed. Safe to call from many threads at once. */
void vo_intersect1(void *scene, const vo_ray *ray, vo_hit *hit);
/* Traces n rays one by one (rtcIntersect1), each exactly as vo_intersect1 would: Embree's
 * packet kernels round differently from its single-ray kernel on some CPUs (AVX2), which made
 * a ray's hit depend on the batch it travelled in. */
void vo_intersect_batch(void *scene, const vo_ray *rays, vo_hit *hits, size_t n);
/* As vo_intersect1, handing `query` to user geometry's intersect callback. */
void vo_intersect1_query(void *scene, const vo_ray *ray, vo_hit *hit, void *query);
/* 1 when anything lies on the ray within [tnear, tfar], else 0. */
int vo_occluded1(void *scene, const vo_ray *ray);
/* Interpolates vertex-attribute slot 0 (the texture coordinate) at a hit. */
void vo_interpolate_uv(void *geometry, uint32_t prim, float u, float v, float out[2]);

#ifdef __cplusplus
}
#endif

#endif
