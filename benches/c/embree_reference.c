/* C reference for the ray-casting benchmark: the same Embree 3 calls luxtally's Rust
   wrapper makes, as plain C loops over the very same SoA rays, on one thread. The
   benchmark reports Rust/C per API; the C side writes the same outputs (t, primID,
   u, v, unit Ng / occlusion flags) so the two do the same work. */
#define _POSIX_C_SOURCE 199309L
#include <embree3/rtcore.h>
#include <math.h>
#include <stddef.h>
#include <time.h>

/* Embree 3's C API names its structs with the `struct` keyword only. */
typedef struct RTCRay RTCRay;
typedef struct RTCRayHit RTCRayHit;
typedef struct RTCRay8 RTCRay8;
typedef struct RTCRayHit8 RTCRayHit8;
typedef struct RTCRay16 RTCRay16;
typedef struct RTCRayHit16 RTCRayHit16;

typedef struct {
  const float *ox, *oy, *oz, *dx, *dy, *dz, *tnear, *tfar;
} LtRays;

typedef struct {
  float *t, *u, *v, *ngx, *ngy, *ngz;
  unsigned *prim;
  unsigned char *occluded;
} LtHits;

enum { API_SINGLE = 0, API_PACKET8 = 1, API_PACKET16 = 2, API_STREAM = 3 };
#define STREAM_CHUNK 256

/* CPU time of the calling thread: one-thread figures stay meaningful when other
   processes share the cores (time slices taken by them do not count). */
double luxtally_thread_cpu_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void store_hit(LtHits *h, size_t i, float tfar, unsigned geom, unsigned prim,
                      float u, float v, float nx, float ny, float nz) {
  if (geom == RTC_INVALID_GEOMETRY_ID) {
    h->t[i] = INFINITY; h->prim[i] = 0xffffffffu;
    h->u[i] = h->v[i] = h->ngx[i] = h->ngy[i] = h->ngz[i] = 0.0f;
    return;
  }
  float inv = 1.0f / sqrtf(nx * nx + ny * ny + nz * nz);
  h->t[i] = tfar; h->prim[i] = prim; h->u[i] = u; h->v[i] = v;
  h->ngx[i] = nx * inv; h->ngy[i] = ny * inv; h->ngz[i] = nz * inv;
}

static void init_ray1(RTCRay *r, const LtRays *s, size_t i) {
  r->org_x = s->ox[i]; r->org_y = s->oy[i]; r->org_z = s->oz[i];
  r->dir_x = s->dx[i]; r->dir_y = s->dy[i]; r->dir_z = s->dz[i];
  r->tnear = s->tnear[i]; r->tfar = s->tfar[i];
  r->time = 0.0f; r->mask = 0xffffffffu; r->id = 0; r->flags = 0;
}

#define FILL_PACKET(P, W, base, n, valid)                                        \
  for (size_t k = 0; k < (W); k++) {                                             \
    size_t i = (base) + (k < (n) ? k : 0);                                       \
    valid[k] = k < (n) ? -1 : 0;                                                 \
    P.org_x[k] = s->ox[i]; P.org_y[k] = s->oy[i]; P.org_z[k] = s->oz[i];         \
    P.dir_x[k] = s->dx[i]; P.dir_y[k] = s->dy[i]; P.dir_z[k] = s->dz[i];         \
    P.tnear[k] = s->tnear[i]; P.tfar[k] = s->tfar[i];                            \
    P.time[k] = 0.0f; P.mask[k] = 0xffffffffu; P.id[k] = 0; P.flags[k] = 0;      \
  }

static void closest(RTCScene scene, const LtRays *s, LtHits *h, size_t n, int api) {
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  if (api == API_SINGLE) {
    for (size_t i = 0; i < n; i++) {
      RTCRayHit rh;
      init_ray1(&rh.ray, s, i);
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID; rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene, &ctx, &rh);
      store_hit(h, i, rh.ray.tfar, rh.hit.geomID, rh.hit.primID, rh.hit.u, rh.hit.v,
                rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    }
  } else if (api == API_PACKET8) {
    for (size_t b = 0; b < n; b += 8) {
      size_t m = n - b < 8 ? n - b : 8;
      RTC_ALIGN(32) int valid[8];
      RTCRayHit8 p;
      FILL_PACKET(p.ray, 8, b, m, valid);
      for (int k = 0; k < 8; k++) p.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect8(valid, scene, &ctx, &p);
      for (size_t k = 0; k < m; k++)
        store_hit(h, b + k, p.ray.tfar[k], p.hit.geomID[k], p.hit.primID[k], p.hit.u[k],
                  p.hit.v[k], p.hit.Ng_x[k], p.hit.Ng_y[k], p.hit.Ng_z[k]);
    }
  } else if (api == API_PACKET16) {
    for (size_t b = 0; b < n; b += 16) {
      size_t m = n - b < 16 ? n - b : 16;
      RTC_ALIGN(64) int valid[16];
      RTCRayHit16 p;
      FILL_PACKET(p.ray, 16, b, m, valid);
      for (int k = 0; k < 16; k++) p.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect16(valid, scene, &ctx, &p);
      for (size_t k = 0; k < m; k++)
        store_hit(h, b + k, p.ray.tfar[k], p.hit.geomID[k], p.hit.primID[k], p.hit.u[k],
                  p.hit.v[k], p.hit.Ng_x[k], p.hit.Ng_y[k], p.hit.Ng_z[k]);
    }
  } else {
    RTCRayHit buf[STREAM_CHUNK];
    for (size_t b = 0; b < n; b += STREAM_CHUNK) {
      size_t m = n - b < STREAM_CHUNK ? n - b : STREAM_CHUNK;
      for (size_t k = 0; k < m; k++) {
        init_ray1(&buf[k].ray, s, b + k);
        buf[k].hit.geomID = RTC_INVALID_GEOMETRY_ID;
        buf[k].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      }
      rtcIntersect1M(scene, &ctx, buf, (unsigned)m, sizeof(RTCRayHit));
      for (size_t k = 0; k < m; k++)
        store_hit(h, b + k, buf[k].ray.tfar, buf[k].hit.geomID, buf[k].hit.primID,
                  buf[k].hit.u, buf[k].hit.v, buf[k].hit.Ng_x, buf[k].hit.Ng_y,
                  buf[k].hit.Ng_z);
    }
  }
}

static void occluded(RTCScene scene, const LtRays *s, LtHits *h, size_t n, int api) {
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  if (api == API_SINGLE) {
    for (size_t i = 0; i < n; i++) {
      RTCRay r;
      init_ray1(&r, s, i);
      rtcOccluded1(scene, &ctx, &r);
      h->occluded[i] = r.tfar == -INFINITY;
    }
  } else if (api == API_PACKET8) {
    for (size_t b = 0; b < n; b += 8) {
      size_t m = n - b < 8 ? n - b : 8;
      RTC_ALIGN(32) int valid[8];
      RTCRay8 p;
      FILL_PACKET(p, 8, b, m, valid);
      rtcOccluded8(valid, scene, &ctx, &p);
      for (size_t k = 0; k < m; k++) h->occluded[b + k] = p.tfar[k] == -INFINITY;
    }
  } else if (api == API_PACKET16) {
    for (size_t b = 0; b < n; b += 16) {
      size_t m = n - b < 16 ? n - b : 16;
      RTC_ALIGN(64) int valid[16];
      RTCRay16 p;
      FILL_PACKET(p, 16, b, m, valid);
      rtcOccluded16(valid, scene, &ctx, &p);
      for (size_t k = 0; k < m; k++) h->occluded[b + k] = p.tfar[k] == -INFINITY;
    }
  } else {
    RTCRay buf[STREAM_CHUNK];
    for (size_t b = 0; b < n; b += STREAM_CHUNK) {
      size_t m = n - b < STREAM_CHUNK ? n - b : STREAM_CHUNK;
      for (size_t k = 0; k < m; k++) init_ray1(&buf[k], s, b + k);
      rtcOccluded1M(scene, &ctx, buf, (unsigned)m, sizeof(RTCRay));
      for (size_t k = 0; k < m; k++) h->occluded[b + k] = buf[k].tfar == -INFINITY;
    }
  }
}

/* Traces the n rays `iterations` times through `api` (0 single, 1 packet8, 2 packet16,
   3 stream), closest hit or occlusion; returns the best thread CPU time of one pass in s. */
double luxtally_c_trace(RTCScene scene, const LtRays *rays, LtHits *hits, size_t n,
                        int api, int occlusion, int iterations) {
  double best = INFINITY;
  for (int it = 0; it < iterations; it++) {
    double t0 = luxtally_thread_cpu_s();
    if (occlusion) occluded(scene, rays, hits, n, api);
    else closest(scene, rays, hits, n, api);
    double dt = luxtally_thread_cpu_s() - t0;
    if (dt < best) best = dt;
  }
  return best;
}
