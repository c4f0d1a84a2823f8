/* Using macrofacet in your own renderer: a complete, plain-C path tracer (no ray-tracing library)
 * that renders two macrofacet media under a sky.
 *
 *   left:  a gold sphere as a thin shell (sigma = 1e-3 of its radius): a rough metal surface;
 *   right: the same sphere as an isotropic Gaussian-process statistical surface with a large
 *          sigma: a fuzzy volume.
 *
 * What the renderer does, and what the library does:
 *   - the renderer owns the geometry: it tells the library where the mean surface is (here with
 *     its own callbacks, mf_surface_new_callbacks; mf_surface_new_sphere / _mesh are built in),
 *     and finds where rays enter and leave each medium's region f < k sigma (an offset sphere);
 *   - inside a region the library owns the volume event: mf_track_free_flight returns the next
 *     collision and its local frame, mf_track_transmittance the transmittance of a shadow ray;
 *   - at a collision the phase function is evaluated (mf_phase_eval_pdf, for next-event
 *     estimation with multiple importance sampling) and sampled (mf_phase_sample) in that frame.
 *
 * Usage: render_spheres [width height spp out.ppm]   (default 320 160 64 spheres.ppm)
 * Prints the image mean; exits 1 on any library error. */
#include <macrofacet.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#define PI 3.14159265358979323846

typedef struct {
  double x, y, z;
} vec3;

static vec3 v(double x, double y, double z) { vec3 r = {x, y, z}; return r; }
static vec3 add(vec3 a, vec3 b) { return v(a.x + b.x, a.y + b.y, a.z + b.z); }
static vec3 sub(vec3 a, vec3 b) { return v(a.x - b.x, a.y - b.y, a.z - b.z); }
static vec3 mul(vec3 a, double s) { return v(a.x * s, a.y * s, a.z * s); }
static double dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static vec3 unit(vec3 a) { return mul(a, 1.0 / sqrt(dot(a, a))); }
static mf_vec3 to_mf(vec3 a) { mf_vec3 r = {a.x, a.y, a.z}; return r; }
static vec3 from_mf(mf_vec3 a) { return v(a.x, a.y, a.z); }

/* ---------------------------------------------------------------- random numbers (splitmix64) */
typedef struct {
  uint64_t state;
} rng;
static uint64_t next_u64(rng *r) {
  uint64_t z = (r->state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
static double next_1d(rng *r) { return (double)(next_u64(r) >> 11) * 0x1.0p-53; }

/* ---------------------------------------------------------------- the mean surface: a sphere */
typedef struct {
  vec3 centre;
  double radius;
} sphere;

/* The signed distance of a sphere (> 0 outside), its gradient as the frame normal, and
 * Mitsuba's dp/du (around the z axis) as the tangent. Returns 0 on success. */
static int32_t sphere_point(void *user_data, mf_vec3 p, mf_surface_point *out) {
  const sphere *s = (const sphere *)user_data;
  vec3 q = sub(from_mf(p), s->centre);
  double r = sqrt(dot(q, q));
  out->f = r - s->radius;
  out->normal = to_mf(r > 0 ? mul(q, 1.0 / r) : v(0, 0, 1));
  out->tangent = to_mf(v(-q.y, q.x, 0));
  return 0;
}

/* The parameter interval of o + t d inside the ball of radius `radius`, if any, with t1 > 0. */
static int ball_interval(vec3 o, vec3 d, vec3 c, double radius, double *t0, double *t1) {
  vec3 oc = sub(o, c);
  double b = dot(oc, d), cc = dot(oc, oc) - radius * radius, disc = b * b - cc;
  if (disc < 0) return 0;
  double s = sqrt(disc);
  *t0 = -b - s;
  *t1 = -b + s;
  return *t1 > 0;
}

/* ---------------------------------------------------------------- the scene */
typedef struct {
  sphere shape;
  mf_medium *medium;
  mf_surface *surface;
  double top; /* the region: f < top (mf_medium_shell_top) */
} object;

#define OBJECTS 2
static object g_objects[OBJECTS];

static void check(mf_status s, const char *what) {
  if (s != MF_OK) {
    char msg[512];
    mf_last_error_message(msg, sizeof msg, NULL);
    fprintf(stderr, "render_spheres: %s: %s: %s\n", what, mf_status_str(s), msg);
    exit(1);
  }
}

static mf_medium *make_medium(double sigma, const char *distribution, double alpha) {
  mf_params *p = NULL;
  mf_medium *m = NULL;
  check(mf_params_new(&p), "mf_params_new");
  check(mf_params_set_float(p, "sigma", sigma), "sigma");
  check(mf_params_set_string(p, "distribution", distribution), "distribution");
  check(mf_params_set_float(p, "alpha", alpha), "alpha");
  check(mf_params_set_string(p, "material", "Au"), "material");
  check(mf_medium_new(p, &m), "mf_medium_new");
  mf_params_free(p);
  return m;
}

static void build_scene(void) {
  g_objects[0].shape = (sphere){v(-1.1, 0, 0), 1.0};
  g_objects[0].medium = make_medium(1e-3, "beckmann", 0.3); /* a thin shell: a surface */
  g_objects[1].shape = (sphere){v(1.1, 0, 0), 0.9};
  g_objects[1].medium = make_medium(0.08, "gpss", 1.0); /* isotropic kernel, large sigma: a volume */
  for (int i = 0; i < OBJECTS; ++i) {
    object *o = &g_objects[i];
    /* Convex: the library bounds a segment from its two end points. The box holds the sphere. */
    vec3 c = o->shape.centre;
    double r = o->shape.radius;
    mf_surface_callbacks cb = {sphere_point, NULL, MF_SURFACE_CONVEX, to_mf(sub(c, v(r, r, r))), to_mf(add(c, v(r, r, r)))};
    check(mf_surface_new_callbacks(&cb, &o->surface), "mf_surface_new_callbacks");
    check(mf_medium_shell_top(o->medium, &o->top), "mf_medium_shell_top");
  }
}

/* The first region boundary along o + t d, t > eps: the object, and whether the ray enters. */
static int next_boundary(vec3 o, vec3 d, double *t, int *which, int *entering) {
  const double eps = 1e-9;
  *t = INFINITY;
  for (int i = 0; i < OBJECTS; ++i) {
    double t0, t1;
    if (!ball_interval(o, d, g_objects[i].shape.centre, g_objects[i].shape.radius + g_objects[i].top, &t0, &t1)) continue;
    if (t0 > eps && t0 < *t) *t = t0, *which = i, *entering = 1;
    else if (t0 <= eps && t1 > eps && t1 < *t) *t = t1, *which = i, *entering = 0;
  }
  return isfinite(*t);
}

/* The transmittance from o along d to infinity through every region it crosses. `hint`: the
   mf_collision::hint of the collision at o, for the first segment (a mesh surface's first query
   starts at the collision's triangle; 0 from this example's callback spheres, and safe always). */
static double shadow(vec3 o, vec3 d, int inside, uint64_t hint, rng *r) {
  double T = 1.0;
  for (int bounce = 0; bounce < 16 && T > 0; ++bounce) {
    double t;
    int which = -1, entering = 0;
    int hit = next_boundary(o, d, &t, &which, &entering);
    if (inside >= 0) {
      object *obj = &g_objects[inside];
      mf_track_query q = {to_mf(o), to_mf(d), hit ? t : INFINITY, next_u64(r), 0, 0, hint};
      mf_transmittance tr;
      check(mf_track_transmittance(obj->medium, obj->surface, NULL, &obj->shape, &q, &tr), "mf_track_transmittance");
      T *= tr.transmittance;
    }
    if (!hit) break;
    o = add(o, mul(d, t));
    inside = entering ? which : -1;
    hint = 0; /* past a boundary the ray no longer starts at the collision */
  }
  return T;
}

/* The sky: dim at the horizon and below, bright overhead. */
static double sky(vec3 d) { return 0.15 + 2.0 * (d.z > 0 ? d.z * d.z : 0); }

/* Power heuristic. */
static double mis(double a, double b) { return a * a / (a * a + b * b); }

/* Radiance along a camera ray: path tracing with next-event estimation of the sky. */
static double radiance(vec3 o, vec3 d, rng *r, double rgb[3]) {
  double beta[3] = {1, 1, 1}, L = 0;
  int inside = -1;
  uint64_t hint = 0;   /* the last collision's mf_collision::hint while the ray starts there */
  double prev_pdf = 0; /* 0: the camera (no MIS) */
  rgb[0] = rgb[1] = rgb[2] = 0;
  for (int depth = 0; depth < 32; ++depth) {
    double t;
    int which = -1, entering = 0;
    int hit = next_boundary(o, d, &t, &which, &entering);
    if (inside >= 0) {
      object *obj = &g_objects[inside];
      mf_track_query q = {to_mf(o), to_mf(d), hit ? t : INFINITY, next_u64(r), 0, 0, hint};
      mf_collision c;
      check(mf_track_free_flight(obj->medium, obj->surface, NULL, &obj->shape, &q, &c), "mf_track_free_flight");
      if (c.scattered) {
        vec3 p = from_mf(c.p);
        mf_vec3 wi = to_mf(mul(d, -1)); /* wi points away from the event */
        /* Next-event estimation: a uniform direction on the sky, MIS with the phase function. */
        double z = 1 - 2 * next_1d(r), phi = 2 * PI * next_1d(r), s = sqrt(fmax(0, 1 - z * z));
        vec3 l = v(s * cos(phi), s * sin(phi), z);
        mf_phase_value pv;
        check(mf_phase_eval_pdf(obj->medium, &c.frame, wi, to_mf(l), &pv), "mf_phase_eval_pdf");
        double light_pdf = 1 / (4 * PI);
        if (pv.pdf > 0 || pv.value.r > 0) {
          double w = mis(light_pdf, pv.pdf) * sky(l) * shadow(p, l, inside, c.hint, r) / light_pdf;
          rgb[0] += beta[0] * pv.value.r * w, rgb[1] += beta[1] * pv.value.g * w, rgb[2] += beta[2] * pv.value.b * w;
        }
        /* Continue by sampling the phase function. */
        double u[MF_PHASE_SAMPLE_DIMENSIONS];
        for (int k = 0; k < MF_PHASE_SAMPLE_DIMENSIONS; ++k) u[k] = next_1d(r);
        mf_phase_sample_result ps;
        check(mf_phase_sample(obj->medium, &c.frame, wi, u, &ps), "mf_phase_sample");
        if (!ps.valid) break;
        beta[0] *= ps.weight.r, beta[1] *= ps.weight.g, beta[2] *= ps.weight.b;
        o = p;
        d = from_mf(ps.wo);
        hint = c.hint; /* the escape flight starts at the collision */
        prev_pdf = ps.pdf;
        continue;
      }
    }
    if (!hit) {
      double w = prev_pdf > 0 ? mis(prev_pdf, 1 / (4 * PI)) : 1;
      rgb[0] += beta[0] * sky(d) * w, rgb[1] += beta[1] * sky(d) * w, rgb[2] += beta[2] * sky(d) * w;
      break;
    }
    /* An index-matched boundary: the ray goes straight on into or out of the region. */
    o = add(o, mul(d, t));
    inside = entering ? which : -1;
    hint = 0;
  }
  L = (rgb[0] + rgb[1] + rgb[2]) / 3;
  return L;
}

int main(int argc, char **argv) {
  int width = argc > 1 ? atoi(argv[1]) : 320, height = argc > 2 ? atoi(argv[2]) : 160;
  int spp = argc > 3 ? atoi(argv[3]) : 64;
  const char *out = argc > 4 ? argv[4] : "spheres.ppm";
  if (width <= 0 || height <= 0 || spp <= 0) {
    fprintf(stderr, "usage: render_spheres [width height spp out.ppm]\n");
    return 2;
  }
  build_scene();
  FILE *f = fopen(out, "wb");
  if (!f) {
    fprintf(stderr, "render_spheres: cannot write %s\n", out);
    return 1;
  }
  fprintf(f, "P6\n%d %d\n255\n", width, height);
  const vec3 eye = v(0, -6, 1.2), target = v(0, 0, 0);
  const vec3 fwd = unit(sub(target, eye)), right = unit(v(fwd.y, -fwd.x, 0));
  const vec3 up = v(right.y * fwd.z - right.z * fwd.y, right.z * fwd.x - right.x * fwd.z, right.x * fwd.y - right.y * fwd.x);
  const double tan_half = tan(0.5 * 40 * PI / 180), aspect = (double)width / height;
  double sum = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      double acc[3] = {0, 0, 0};
      rng r = {((uint64_t)y << 32 | (uint64_t)x) * 0x9E3779B97F4A7C15ull};
      for (int s = 0; s < spp; ++s) {
        double px = (2 * (x + next_1d(&r)) / width - 1) * tan_half * aspect;
        double py = (1 - 2 * (y + next_1d(&r)) / height) * tan_half;
        vec3 d = unit(add(fwd, add(mul(right, px), mul(up, py))));
        double rgb[3];
        radiance(eye, d, &r, rgb);
        for (int c = 0; c < 3; ++c) acc[c] += rgb[c] / spp;
      }
      unsigned char pixel[3];
      for (int c = 0; c < 3; ++c) {
        double l = acc[c] <= 0.0031308 ? 12.92 * acc[c] : 1.055 * pow(acc[c], 1 / 2.4) - 0.055; /* sRGB */
        pixel[c] = (unsigned char)(255 * fmin(fmax(l, 0), 1) + 0.5);
        sum += acc[c] / 3;
      }
      fwrite(pixel, 1, 3, f);
    }
  }
  fclose(f);
  for (int i = 0; i < OBJECTS; ++i) {
    mf_surface_free(g_objects[i].surface);
    mf_medium_free(g_objects[i].medium);
  }
  double mean = sum / ((double)width * height);
  printf("render_spheres: %dx%d, %d spp -> %s, mean radiance %.4f\n", width, height, spp, out, mean);
  return isfinite(mean) && mean > 0 ? 0 : 1;
}
