/*
 * embree_shim.c - implementation of embree_shim.h for Embree 3.13 and Embree 4.x.
 *
 * build.rs defines VO_EMBREE_MAJOR (3 or 4) to pick the header directory; from there on every
 * difference between the two APIs is decided on RTC_VERSION_MAJOR, which the chosen header
 * defines, so a mismatched define cannot silently compile the wrong branch.
 */
#include "embree_shim.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <pmmintrin.h>
#include <xmmintrin.h>

#if VO_EMBREE_MAJOR == 4
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif

#if RTC_VERSION_MAJOR != 3 && RTC_VERSION_MAJOR != 4
#error "embree_shim supports Embree 3 and Embree 4 only"
#endif
#if RTC_VERSION_MAJOR != VO_EMBREE_MAJOR
#error "the Embree headers found do not match VO_EMBREE_MAJOR"
#endif

/* Embree's error callback has an enum parameter; the shim's has an int so that the Rust side
 * does not depend on Embree's enum. This adapter sits between them. */
typedef struct vo_error_sink {
  vo_error_fn fn;
  void *user;
} vo_error_sink;

typedef struct vo_device_box {
  RTCDevice device;
  vo_error_sink sink;
  /* Bytes Embree holds for this device now, and the most it has held (memory monitor). */
  _Atomic long long bytes;
  _Atomic long long peak;
} vo_device_box;

/* Embree's memory monitor: called from any thread for each allocation (bytes > 0) and release
 * (bytes < 0), once, before or after it happens. Nothing is ever cancelled here, so every call
 * counts. */
static bool vo_on_memory(void *user, ssize_t bytes, bool post) {
  vo_device_box *box = (vo_device_box *)user;
  (void)post;
  long long now = atomic_fetch_add(&box->bytes, (long long)bytes) + (long long)bytes;
  long long peak = atomic_load(&box->peak);
  while (now > peak && !atomic_compare_exchange_weak(&box->peak, &peak, now)) {
  }
  return true;
}

static void vo_on_error(void *user, enum RTCError code, const char *message) {
  vo_error_sink *sink = (vo_error_sink *)user;
  if (sink && sink->fn) sink->fn(sink->user, (int)code, message ? message : "");
}

vo_version vo_compiled_version(void) {
  vo_version v = {RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH};
  return v;
}

void *vo_device_new(const char *config, vo_error_fn on_error, void *user) {
  vo_device_box *box = (vo_device_box *)calloc(1, sizeof(vo_device_box));
  if (!box) return NULL;
  box->sink.fn = on_error;
  box->sink.user = user;
  box->device = rtcNewDevice(config);
  if (!box->device) {
    /* rtcNewDevice reports its failure through rtcGetDeviceError(NULL) only. */
    if (on_error) on_error(user, (int)rtcGetDeviceError(NULL), "rtcNewDevice failed");
    free(box);
    return NULL;
  }
  rtcSetDeviceErrorFunction(box->device, vo_on_error, &box->sink);
  atomic_init(&box->bytes, 0);
  atomic_init(&box->peak, 0);
  rtcSetDeviceMemoryMonitorFunction(box->device, vo_on_memory, box);
  return box;
}

void vo_device_memory(void *device, long long *bytes, long long *peak) {
  vo_device_box *box = (vo_device_box *)device;
  *bytes = atomic_load(&box->bytes);
  *peak = atomic_load(&box->peak);
}

void vo_device_release(void *device) {
  vo_device_box *box = (vo_device_box *)device;
  if (!box) return;
  rtcReleaseDevice(box->device);
  free(box);
}

int vo_device_take_error(void *device) {
  vo_device_box *box = (vo_device_box *)device;
  return box ? (int)rtcGetDeviceError(box->device) : (int)rtcGetDeviceError(NULL);
}

vo_version vo_device_version(void *device) {
  vo_device_box *box = (vo_device_box *)device;
  vo_version v = {(int)rtcGetDeviceProperty(box->device, RTC_DEVICE_PROPERTY_VERSION_MAJOR),
                  (int)rtcGetDeviceProperty(box->device, RTC_DEVICE_PROPERTY_VERSION_MINOR),
                  (int)rtcGetDeviceProperty(box->device, RTC_DEVICE_PROPERTY_VERSION_PATCH)};
  return v;
}

size_t vo_describe(const char *config, char *buf, size_t len) {
  /* Embree prints its CPU/ISA/thread report to stdout only, with verbose=1; redirect file
   * descriptor 1 into a temporary file for the lifetime of one probe device. */
  if (!buf || len == 0) return 0;
  buf[0] = '\0';
  char cfg[512];
  snprintf(cfg, sizeof cfg, "%s%sverbose=1", config ? config : "", (config && *config) ? "," : "");
  FILE *tmp = tmpfile();
  if (!tmp) return 0;
  fflush(stdout);
  int saved = dup(1);
  if (saved < 0) {
    fclose(tmp);
    return 0;
  }
  dup2(fileno(tmp), 1);
  RTCDevice d = rtcNewDevice(cfg);
  if (d) rtcReleaseDevice(d);
  fflush(stdout);
  dup2(saved, 1);
  close(saved);
  rewind(tmp);
  size_t n = fread(buf, 1, len - 1, tmp);
  buf[n] = '\0';
  fclose(tmp);
  return n;
}

void vo_flush_denormals(void) {
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}

static RTCDevice vo_raw(void *device) { return ((vo_device_box *)device)->device; }

static enum RTCBuildQuality vo_rtc_quality(vo_quality q) {
  switch (q) {
    case VO_QUALITY_LOW: return RTC_BUILD_QUALITY_LOW;
    case VO_QUALITY_HIGH: return RTC_BUILD_QUALITY_HIGH;
    case VO_QUALITY_REFIT: return RTC_BUILD_QUALITY_REFIT;
    default: return RTC_BUILD_QUALITY_MEDIUM;
  }
}

void *vo_scene_new(void *device, vo_quality quality, uint32_t flags) {
  RTCScene scene = rtcNewScene(vo_raw(device));
  if (!scene) return NULL;
  /* A scene's build quality has no REFIT level; refit applies to geometries only, and Embree
   * honours a geometry's quality only in the two-level structure it builds for a scene of LOW
   * quality (rtcSetGeometryBuildQuality(3)). */
  rtcSetSceneBuildQuality(scene, quality == VO_QUALITY_REFIT ? RTC_BUILD_QUALITY_LOW : vo_rtc_quality(quality));
  int f = RTC_SCENE_FLAG_NONE;
  if (flags & VO_SCENE_COMPACT) f |= RTC_SCENE_FLAG_COMPACT;
  if (flags & VO_SCENE_ROBUST) f |= RTC_SCENE_FLAG_ROBUST;
  if (quality == VO_QUALITY_REFIT) f |= RTC_SCENE_FLAG_DYNAMIC;
  rtcSetSceneFlags(scene, (enum RTCSceneFlags)f);
  return scene;
}

void vo_scene_release(void *scene) {
  if (scene) rtcReleaseScene((RTCScene)scene);
}

void *vo_scene_attach_triangles(void *device, void *scene, vo_quality quality, const float *positions,
                                size_t vertex_count, const uint32_t *indices, size_t triangle_count,
                                const float *uvs, uint32_t *geom_id) {
  RTCGeometry g = rtcNewGeometry(vo_raw(device), RTC_GEOMETRY_TYPE_TRIANGLE);
  if (!g) return NULL;
  rtcSetGeometryBuildQuality(g, vo_rtc_quality(quality));
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, positions, 0, 3 * sizeof(float),
                             vertex_count);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices, 0, 3 * sizeof(uint32_t),
                             triangle_count);
  if (uvs) {
    rtcSetGeometryVertexAttributeCount(g, 1);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX_ATTRIBUTE, 0, RTC_FORMAT_FLOAT2, uvs, 0,
                               2 * sizeof(float), vertex_count);
  }
  rtcCommitGeometry(g);
  unsigned id = rtcAttachGeometry((RTCScene)scene, g);
  /* The scene now holds a reference; the handle stays valid for the scene's lifetime. */
  rtcReleaseGeometry(g);
  if (geom_id) *geom_id = id;
  return g;
}

void *vo_scene_attach_grids(void *device, void *scene, vo_quality quality, const float *positions,
                            size_t vertex_count, const vo_grid *grids, size_t grid_count, uint32_t *geom_id) {
  RTCGeometry g = rtcNewGeometry(vo_raw(device), RTC_GEOMETRY_TYPE_GRID);
  if (!g) return NULL;
  rtcSetGeometryBuildQuality(g, vo_rtc_quality(quality));
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, positions, 0, 3 * sizeof(float),
                             vertex_count);
  struct RTCGrid *out = (struct RTCGrid *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_GRID, 0, RTC_FORMAT_GRID,
                                                                  sizeof(struct RTCGrid), grid_count);
  if (!out) {
    rtcReleaseGeometry(g);
    return NULL;
  }
  for (size_t i = 0; i < grid_count; i++) {
    out[i].startVertexID = grids[i].start;
    out[i].stride = grids[i].stride;
    out[i].width = grids[i].width;
    out[i].height = grids[i].height;
  }
  rtcCommitGeometry(g);
  unsigned id = rtcAttachGeometry((RTCScene)scene, g);
  rtcReleaseGeometry(g);
  if (geom_id) *geom_id = id;
  return g;
}

void *vo_scene_attach_instance(void *device, void *scene, void *child, const float xfm[12], uint32_t *geom_id) {
  RTCGeometry g = rtcNewGeometry(vo_raw(device), RTC_GEOMETRY_TYPE_INSTANCE);
  if (!g) return NULL;
  rtcSetGeometryInstancedScene(g, (RTCScene)child);
  rtcSetGeometryTimeStepCount(g, 1);
  rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
  rtcCommitGeometry(g);
  unsigned id = rtcAttachGeometry((RTCScene)scene, g);
  rtcReleaseGeometry(g);
  if (geom_id) *geom_id = id;
  return g;
}

void vo_scene_commit(void *scene) { rtcCommitScene((RTCScene)scene); }

void vo_scene_refit(void *scene, void *geometry, void *second) {
  rtcUpdateGeometryBuffer((RTCGeometry)geometry, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry((RTCGeometry)geometry);
  if (second) {
    rtcUpdateGeometryBuffer((RTCGeometry)second, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry((RTCGeometry)second);
  }
  rtcCommitScene((RTCScene)scene);
}

void vo_scene_bounds(void *scene, float lower[3], float upper[3]) {
  struct RTCBounds b;
  rtcGetSceneBounds((RTCScene)scene, &b);
  lower[0] = b.lower_x;
  lower[1] = b.lower_y;
  lower[2] = b.lower_z;
  upper[0] = b.upper_x;
  upper[1] = b.upper_y;
  upper[2] = b.upper_z;
}

static void vo_fill_ray(struct RTCRay *r, const vo_ray *in) {
  r->org_x = in->org[0];
  r->org_y = in->org[1];
  r->org_z = in->org[2];
  r->tnear = in->tnear;
  r->dir_x = in->dir[0];
  r->dir_y = in->dir[1];
  r->dir_z = in->dir[2];
  r->time = 0.0f;
  r->tfar = in->tfar;
  /* All ones: Debian builds Embree with ray masks enabled, and Embree 3 and 4 differ in the
   * default geometry mask; an all-ones ray mask hits either. */
  r->mask = 0xFFFFFFFFu;
  r->id = 0;
  r->flags = 0;
}

/* A query context that carries the caller's per-ray pointer to user geometry callbacks: Embree
 * hands the callbacks the context it was given, so one that begins with Embree's own can be
 * extended (Embree's documented way to pass per-ray data). */
#if RTC_VERSION_MAJOR >= 4
typedef struct vo_context {
  struct RTCRayQueryContext ctx;
  void *query;
} vo_context;
#else
typedef struct vo_context {
  struct RTCIntersectContext ctx;
  void *query;
} vo_context;
#endif

static void vo_user_bounds(const struct RTCBoundsFunctionArguments *args) {
  const vo_user_geometry *g = (const vo_user_geometry *)args->geometryUserPtr;
  float lo[3], hi[3];
  g->bounds(g->user, args->primID, lo, hi);
  args->bounds_o->lower_x = lo[0];
  args->bounds_o->lower_y = lo[1];
  args->bounds_o->lower_z = lo[2];
  args->bounds_o->upper_x = hi[0];
  args->bounds_o->upper_y = hi[1];
  args->bounds_o->upper_z = hi[2];
}

/* The caller's test on one ray (N = 1: the shim only traces single rays). */
static int vo_user_test(const vo_user_geometry *g, const vo_context *c, unsigned prim, const struct RTCRay *r,
                        float *t, float *u, float *v) {
  vo_ray in = {{r->org_x, r->org_y, r->org_z}, r->tnear, {r->dir_x, r->dir_y, r->dir_z}, r->tfar};
  return g->intersect(g->user, c->query, prim, &in, t, u, v);
}

static void vo_user_intersect(const struct RTCIntersectFunctionNArguments *args) {
  if (args->N != 1 || !args->valid[0]) return;
  const vo_user_geometry *g = (const vo_user_geometry *)args->geometryUserPtr;
  struct RTCRayHit *rh = (struct RTCRayHit *)args->rayhit;
  float t, u, v;
  if (!vo_user_test(g, (const vo_context *)args->context, args->primID, &rh->ray, &t, &u, &v)) return;
  rh->ray.tfar = t;
  rh->hit.u = u;
  rh->hit.v = v;
  rh->hit.Ng_x = 0.0f;
  rh->hit.Ng_y = 1.0f;
  rh->hit.Ng_z = 0.0f;
  rh->hit.primID = args->primID;
  rh->hit.geomID = args->geomID;
  rh->hit.instID[0] = args->context->instID[0];
}

static void vo_user_occluded(const struct RTCOccludedFunctionNArguments *args) {
  if (args->N != 1 || !args->valid[0]) return;
  const vo_user_geometry *g = (const vo_user_geometry *)args->geometryUserPtr;
  struct RTCRay *r = (struct RTCRay *)args->ray;
  float t, u, v;
  if (vo_user_test(g, (const vo_context *)args->context, args->primID, r, &t, &u, &v)) r->tfar = -INFINITY;
}

void *vo_scene_attach_user(void *device, void *scene, vo_quality quality, size_t prim_count,
                           const vo_user_geometry *callbacks, uint32_t *geom_id) {
  RTCGeometry g = rtcNewGeometry(vo_raw(device), RTC_GEOMETRY_TYPE_USER);
  if (!g) return NULL;
  rtcSetGeometryBuildQuality(g, vo_rtc_quality(quality));
  rtcSetGeometryUserPrimitiveCount(g, (unsigned)prim_count);
  rtcSetGeometryUserData(g, (void *)callbacks);
  rtcSetGeometryBoundsFunction(g, vo_user_bounds, NULL);
  rtcSetGeometryIntersectFunction(g, vo_user_intersect);
  rtcSetGeometryOccludedFunction(g, vo_user_occluded);
  rtcCommitGeometry(g);
  unsigned id = rtcAttachGeometry((RTCScene)scene, g);
  rtcReleaseGeometry(g);
  if (geom_id) *geom_id = id;
  return g;
}

static void vo_intersect_context(void *scene, const vo_ray *ray, vo_hit *hit, void *query) {
  struct RTCRayHit rh;
  vo_fill_ray(&rh.ray, ray);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  vo_context c;
  c.query = query;
#if RTC_VERSION_MAJOR >= 4
  rtcInitRayQueryContext(&c.ctx);
  struct RTCIntersectArguments args;
  rtcInitIntersectArguments(&args);
  args.context = &c.ctx;
  rtcIntersect1((RTCScene)scene, &rh, &args);
#else
  rtcInitIntersectContext(&c.ctx);
  rtcIntersect1((RTCScene)scene, &c.ctx, &rh);
#endif
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
    hit->t = ray->tfar;
    hit->u = hit->v = 0.0f;
    hit->prim = VO_INVALID_ID;
    hit->geom = VO_INVALID_ID;
    hit->inst = VO_INVALID_ID;
    hit->ng[0] = hit->ng[1] = hit->ng[2] = 0.0f;
    return;
  }
  hit->t = rh.ray.tfar;
  hit->u = rh.hit.u;
  hit->v = rh.hit.v;
  hit->prim = rh.hit.primID;
  hit->geom = rh.hit.geomID;
  hit->inst = rh.hit.instID[0];
  hit->ng[0] = rh.hit.Ng_x;
  hit->ng[1] = rh.hit.Ng_y;
  hit->ng[2] = rh.hit.Ng_z;
}

void vo_intersect1(void *scene, const vo_ray *ray, vo_hit *hit) { vo_intersect_context(scene, ray, hit, NULL); }

void vo_intersect1_query(void *scene, const vo_ray *ray, vo_hit *hit, void *query) {
  vo_intersect_context(scene, ray, hit, query);
}

/* Not rtcIntersect16: see the header. One call per batch still saves the Rust side a foreign
 * call per ray; packets were no faster on the default scene (trace 3.03 s single, 3.07 s
 * packets, medians of six). */
void vo_intersect_batch(void *scene, const vo_ray *rays, vo_hit *hits, size_t n) {
  for (size_t i = 0; i < n; ++i) vo_intersect1(scene, &rays[i], &hits[i]);
}

int vo_occluded1(void *scene, const vo_ray *ray) {
  struct RTCRay r;
  vo_fill_ray(&r, ray);
  vo_context c;
  c.query = NULL;
#if RTC_VERSION_MAJOR >= 4
  rtcInitRayQueryContext(&c.ctx);
  struct RTCOccludedArguments args;
  rtcInitOccludedArguments(&args);
  args.context = &c.ctx;
  rtcOccluded1((RTCScene)scene, &r, &args);
#else
  rtcInitIntersectContext(&c.ctx);
  rtcOccluded1((RTCScene)scene, &c.ctx, &r);
#endif
  /* Embree marks an occluded ray by setting tfar to -inf. */
  return r.tfar < 0.0f ? 1 : 0;
}

void vo_interpolate_uv(void *geometry, uint32_t prim, float u, float v, float out[2]) {
  rtcInterpolate0((RTCGeometry)geometry, prim, u, v, RTC_BUFFER_TYPE_VERTEX_ATTRIBUTE, 0, out, 2);
}
