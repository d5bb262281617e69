/* scatter/main.c: nbt-scatter, screen-space multiple scattering of a render
 * (RGB + depth) through a homogeneous medium (doc/screenspace.md). */
#include <config.h>
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <nbt/nbt.h>
#include <nbt/image.h>
#include "../gen/cli.h"
#include "../gen/preview.h"
#include "scatter.h"
#ifdef HAVE_OPENVDB
#include "vdb_shim.h"
#endif
#ifdef HAVE_GL
#include <nbt/gl_scatter.h>
#include "../examples/egl_headless.h"
#endif

#ifdef HAVE_GL
static const char *gl_method_names(void)
{
    static char buf[256];
    size_t off = 0;
    for (int m = 0; m < NBT_GLS_NMETHODS && off < sizeof buf; m++)
        off += (size_t)snprintf(buf + off, sizeof buf - off, "%s%s", m ? ", " : "", nbt_gls_method_name((nbt_gls_method)m));
    return buf;
}
#endif

static void help(void)
{
    puts("Usage: nbt-scatter IN.exr -o OUT.exr --fov-y DEG --sigma-t X --albedo A (--B B | --dtheta DEG) [options]\n"
         "       nbt-scatter scene NAME -o IN.exr [--size WxH]\n"
         "       nbt-scatter --version\n\n"
         "Applies multiple scattering in a homogeneous medium to a render. IN.exr holds R, G, B\n"
         "(A ignored) and Z as Blender writes it: planar depth along the view axis, sky at\n"
         "Z >= 1e10 (or inf). OUT.exr gets float R, G, B of the whole image, T c + S (direct plus\n"
         "scattered), and Z; OUT.png a tone-mapped preview.\n\n"
         "  -o, --output OUT.exr   output (required)\n"
         "  --fov-y DEG            vertical field of view, (0, 180)\n"
         "  --sigma-t X            extinction coefficient per scene unit, > 0\n"
         "  --albedo A             single-scattering albedo, [0, 1]\n"
         "  --B B | --dtheta DEG   Gaussian phase width: B > 0, or dtheta in (0, 90] degrees (dtheta^2 = 4B)\n"
         "  --method M             ref-a: operator A, every pixel pair through the nearer pixel's kernel\n"
         "                         (Shinya et al., corrected); ref-b: operator B, every source its own Gaussian\n"
         "                         (Elek et al.'s PSF). Both exact on the CPU. On GL (4.3 compute, Mesa's\n"
         "                         llvmpipe without a GPU): nbt (operator A from fitted pyramid weights, exact\n"
         "                         near taps and depth slabs; the default in builds with GL, else ref-a),\n"
         "                         shinya (operator A, windowed), shinya-literal (Alg. 1-4 as printed),\n"
         "                         naive (one pyramid read), elek (Elek et al.)\n"
         "  --cut C                shinya: window radius in beta (3)\n"
         "  --eps E                elek: smoothstep width of the level masks (0.1)\n"
         "  --kernel K             moment (default for ref-a), smallangle, single, lineint, elek (default for\n"
         "                         ref-b), corrected (needs --correction FILE from nbt-fit kernel --correction)\n"
         "  --depth plane|ray      what Z holds: planar depth (default) or distance along the ray\n"
         "  --layers N             use the exact layered FFT when Z takes at most N distinct values\n"
         "                         (default 64), else brute force; --layers 0 forces brute force\n"
         "  --quantize L           approximate: snap the ray distances to L log-spaced layers and use the FFT\n"
         "                         (T stays exact); measure the error against brute force with --compare\n"
         "  --tail X               truncate each kernel where less than X of its mass lies outside (1e-7)\n"
         "  --threads N            0 = all cores (default)\n"
         "  --compare REF.exr      print 'relL1 X relRMS X edge X bias X max X' for the scattered part\n"
         "                         against REF.exr (an nbt-scatter output for the same input and medium)\n"
         "  --no-png               no preview\n"
         "  --density FILE         heterogeneous medium: a density grid (.raw: nbt's raw grid; .vdb: OpenVDB,\n"
         "                         the float grid 'density' or --grid NAME) scaling sigma_t; per-pixel kernels\n"
         "                         from eq. 28/29 along each view ray (ref-a, moment kernel). The grid's box\n"
         "                         must hold the camera and every visible surface.\n"
         "  --camera X,Y,Z --look-at X,Y,Z --up X,Y,Z\n"
         "                         the camera in the grid's world (default 0,0,0 looking at 0,0,-1, up 0,1,0)\n"
         "  --step S               ray-march step in world units (default half a voxel)\n\n"
         "'scene NAME' writes a generated test render: plane, step, layers, slant, blocks (default\n"
         "size 320x240). Exit status: 0 success, 1 failure, 2 bad usage.");
}

static void parse_size(const char *arg, size_t *w, size_t *h)
{
    char *end;
    errno = 0;
    long a = strtol(arg, &end, 10), b = 0;
    int ok = end != arg && *end == 'x';
    if (ok) {
        const char *p = end + 1;
        b = strtol(p, &end, 10);
        ok = end != p && *end == '\0' && errno == 0;
    }
    if (!ok || a < 1 || b < 1 || a > 16384 || b > 16384)
        die_usage("--size: '%s' is not accepted: expected WxH with 1 <= W, H <= 16384", arg);
    *w = (size_t)a;
    *h = (size_t)b;
}

/* the directory of path must exist and be writable: checked before any work */
static void parse_vec3(const char *opt, const char *arg, double v[3])
{
    char *end;
    const char *p = arg;
    for (int i = 0; i < 3; i++) {
        errno = 0;
        v[i] = strtod(p, &end);
        if (end == p || errno == ERANGE || !isfinite(v[i]) || *end != (i < 2 ? ',' : '\0'))
            die_usage("%s: '%s' is not accepted: expected X,Y,Z (three finite numbers)", opt, arg);
        p = end + 1;
    }
}

static char *png_path(const char *out)
{
    size_t n = strlen(out);
    char *p = malloc(n + 5);
    if (!p)
        die("out of memory");
    memcpy(p, out, n + 1);
    if (n > 4 && !strcasecmp(out + n - 4, ".exr"))
        p[n - 4] = '\0';
    strcat(p, ".png");
    return p;
}

static int cmd_scene(int argc, char **argv)
{
    const char *out = NULL;
    size_t w = 320, h = 240;
    static const struct option lo[] = {{"output", 1, 0, 'o'}, {"size", 1, 0, 's'}, {"help", 0, 0, 'h'}, {0, 0, 0, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "o:h", lo, NULL)) != -1) {
        if (c == 'o')
            out = optarg;
        else if (c == 's')
            parse_size(optarg, &w, &h);
        else if (c == 'h') {
            help();
            return 0;
        } else
            die_usage("see 'nbt-scatter --help'");
    }
    if (optind + 1 != argc)
        die_usage("scene: name one scene: %s", scene_names());
    int kind = scene_parse(argv[optind]);
    if (kind < 0)
        die_usage("scene: '%s' is not accepted: expected one of %s", argv[optind], scene_names());
    if (!out)
        die_usage("scene: -o OUT.exr is required");
    check_writable("-o", out);
    nbt_image *im = scene_make(kind, w, h);
    if (!im)
        die("out of memory");
    char err[512];
    if (nbt_image_write_exr(im, out, NULL, 0, err, sizeof err) != NBT_OK)
        die("%s", err);
    nbt_image_free(im);
    return 0;
}

typedef struct {
    const char *in, *out, *compare, *corr_path, *density, *grid_name;
    double fov, sigma_t, albedo, B, tail, step;
    double cam[3], look[3], up[3];
    int method; /* 0: ref-a, 1: ref-b, 2: a GL method */
    int gl_method;
    double cut, eps;
    const char *method_name;
    int kernel; /* -1: the method's default */
    int ray_depth, png;
    long layers, threads, quantize;
} opts;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void parse(int argc, char **argv, opts *o)
{
    enum { O_FOV = 256, O_ST, O_ALB, O_B, O_DTH, O_METHOD, O_KERNEL, O_DEPTH, O_LAYERS, O_TAIL, O_THREADS, O_CMP,
           O_NOPNG, O_CORR, O_DENS, O_GRID, O_CAM, O_LOOK, O_UP, O_STEP, O_QUANT, O_CUT, O_EPS };
    static const struct option lo[] = {
        {"output", 1, 0, 'o'},    {"fov-y", 1, 0, O_FOV},     {"sigma-t", 1, 0, O_ST},    {"albedo", 1, 0, O_ALB},
        {"B", 1, 0, O_B},         {"dtheta", 1, 0, O_DTH},    {"method", 1, 0, O_METHOD}, {"kernel", 1, 0, O_KERNEL},
        {"depth", 1, 0, O_DEPTH}, {"layers", 1, 0, O_LAYERS}, {"tail", 1, 0, O_TAIL},     {"threads", 1, 0, O_THREADS},
        {"compare", 1, 0, O_CMP}, {"no-png", 0, 0, O_NOPNG},  {"correction", 1, 0, O_CORR}, {"help", 0, 0, 'h'},
        {"density", 1, 0, O_DENS},  {"grid", 1, 0, O_GRID},     {"camera", 1, 0, O_CAM},    {"look-at", 1, 0, O_LOOK},
        {"up", 1, 0, O_UP},         {"step", 1, 0, O_STEP},     {"quantize", 1, 0, O_QUANT},
        {"cut", 1, 0, O_CUT},       {"eps", 1, 0, O_EPS},
        {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->fov = o->sigma_t = o->albedo = o->B = NAN;
    o->tail = 1e-7;
    o->kernel = -1;
    o->png = 1;
#ifdef HAVE_GL
    o->method_name = "nbt";
    o->method = 2;
    o->gl_method = NBT_GLS_NBT;
#else
    o->method_name = "ref-a";
#endif
    o->cut = 3.0;
    o->eps = 0.1;
    o->layers = 64;
    o->look[2] = -1; /* camera at the origin looking down -z, +y up (OpenGL's camera space) */
    o->up[1] = 1;
    int c;
    nbt_skernel_kind kk;
    while ((c = getopt_long(argc, argv, "o:h", lo, NULL)) != -1) {
        switch (c) {
        case 'o': o->out = optarg; break;
        case O_FOV: o->fov = opt_double("--fov-y", optarg, 0, 1, 180, 1); break;
        case O_ST: o->sigma_t = opt_double("--sigma-t", optarg, 0, 1, 1e6, 0); break;
        case O_ALB: o->albedo = opt_double("--albedo", optarg, 0, 0, 1, 0); break;
        case O_B:
            if (!isnan(o->B))
                die_usage("--B and --dtheta: give one phase width");
            o->B = opt_double("--B", optarg, 0, 1, 1, 0);
            break;
        case O_DTH: {
            if (!isnan(o->B))
                die_usage("--B and --dtheta: give one phase width");
            double d = opt_double("--dtheta", optarg, 0, 1, 90, 0) * M_PI / 180.0;
            o->B = d * d / 4.0;
            break;
        }
        case O_METHOD:
            o->method_name = optarg;
            if (!strcmp(optarg, "ref-a"))
                o->method = 0;
            else if (!strcmp(optarg, "ref-b"))
                o->method = 1;
            else {
#ifdef HAVE_GL
                nbt_gls_method gm;
                if (nbt_gls_method_parse(optarg, &gm) != NBT_OK)
                    die_usage("--method: '%s' is not accepted: expected ref-a, ref-b or a GL method (%s)", optarg,
                              gl_method_names());
                o->method = 2;
                o->gl_method = (int)gm;
#else
                die_usage("--method: '%s' is not accepted: expected ref-a or ref-b (this build has no GL)", optarg);
#endif
            }
            break;
        case O_KERNEL:
            if (nbt_skernel_parse(optarg, &kk) != NBT_OK)
                die_usage("--kernel: '%s' is not accepted: expected moment, smallangle, corrected, single, lineint "
                          "or elek", optarg);
            o->kernel = (int)kk;
            break;
        case O_DEPTH:
            if (strcmp(optarg, "plane") && strcmp(optarg, "ray"))
                die_usage("--depth: '%s' is not accepted: expected plane or ray", optarg);
            o->ray_depth = !strcmp(optarg, "ray");
            break;
        case O_LAYERS: o->layers = opt_long("--layers", optarg, 0, 4096); break;
        case O_TAIL: o->tail = opt_double("--tail", optarg, 0, 1, 0.1, 0); break;
        case O_THREADS: o->threads = opt_long("--threads", optarg, 0, 64); break;
        case O_CMP: o->compare = optarg; break;
        case O_NOPNG: o->png = 0; break;
        case O_CORR: o->corr_path = optarg; break;
        case O_DENS: o->density = optarg; break;
        case O_GRID: o->grid_name = optarg; break;
        case O_CAM: parse_vec3("--camera", optarg, o->cam); break;
        case O_LOOK: parse_vec3("--look-at", optarg, o->look); break;
        case O_UP: parse_vec3("--up", optarg, o->up); break;
        case O_STEP: o->step = opt_double("--step", optarg, 0, 1, 1e30, 0); break;
        case O_QUANT: o->quantize = opt_long("--quantize", optarg, 2, 4096); break;
        case O_CUT: o->cut = opt_double("--cut", optarg, 0, 1, 100, 0); break;
        case O_EPS: o->eps = opt_double("--eps", optarg, 0, 0, 100, 0); break;
        case 'h': help(); exit(0);
        default: die_usage("see 'nbt-scatter --help'");
        }
    }
    if (optind + 1 != argc)
        die_usage("name one input render IN.exr (see 'nbt-scatter --help')");
    o->in = argv[optind];
    if (!o->out)
        die_usage("-o OUT.exr is required");
    if (isnan(o->fov))
        die_usage("--fov-y DEG is required: the vertical field of view in (0, 180)");
    if (isnan(o->sigma_t))
        die_usage("--sigma-t X is required: the extinction coefficient, > 0");
    if (isnan(o->albedo))
        die_usage("--albedo A is required: in [0, 1]");
    if (isnan(o->B))
        die_usage("--B B or --dtheta DEG is required: the phase function's width");
    if (o->kernel < 0)
        o->kernel = o->method == 1 ? NBT_SKERNEL_ELEK : NBT_SKERNEL_MOMENT;
    if (o->method == 2 && (o->kernel == NBT_SKERNEL_LINEINT || o->kernel == NBT_SKERNEL_ELEK ||
                           o->kernel == NBT_SKERNEL_SINGLE))
        die_usage("--kernel %s: the GL methods take one erfc kernel per pixel (moment, smallangle, corrected); "
                  "elek's Gaussian comes with --method elek", nbt_skernel_name((nbt_skernel_kind)o->kernel));
    if (o->method == 2 && o->quantize)
        die_usage("--quantize belongs to the CPU references");
    if (o->density && o->quantize)
        die_usage("--quantize and --density: per-pixel kernels have no layers to quantise");
    if (o->density && (o->method == 1 || o->kernel != NBT_SKERNEL_MOMENT))
        die_usage("--density: heterogeneous media use operator A with the moment kernel (eq. 28/29): "
                  "--method ref-a or a GL method, --kernel moment");
    if ((o->kernel == NBT_SKERNEL_CORRECTED) != (o->corr_path != NULL))
        die_usage("--kernel corrected and --correction FILE go together");
}

/* the render as the operators need it: distances along the ray */
static float *ray_distances(const opts *o, const nbt_image *im, double dtheta)
{
    size_t np = im->w * im->h;
    float *D = malloc(np * sizeof *D);
    if (!D)
        die("out of memory");
    for (size_t y = 0; y < im->h; y++)
        for (size_t x = 0; x < im->w; x++) {
            size_t i = y * im->w + x;
            double Z = im->z[i];
            if (isnan(Z) || Z < 0)
                die_usage("%s: depth Z at pixel (%zu, %zu) is %g: expected >= 0 (sky: >= 1e10 or inf)", o->in, x, y,
                          Z);
            if (Z >= NBT_SCREEN_SKY)
                D[i] = INFINITY;
            else
                D[i] = (float)(o->ray_depth ? Z : nbt_screen_ray_distance(Z, im->w, im->h, dtheta, x, y));
        }
    for (size_t i = 0; i < 3 * np; i++)
        if (!isfinite(im->rgb[i]))
            die_usage("%s: colour at pixel (%zu, %zu) is not finite", o->in, (i / 3) % im->w, (i / 3) / im->w);
    return D;
}

/* the density grid: nbt's raw format, or OpenVDB through the shim */
static nbt_grid *load_grid(const opts *o)
{
    char err[512];
    nbt_grid *g = NULL;
    size_t n = strlen(o->density);
    if (n > 4 && !strcasecmp(o->density + n - 4, ".vdb")) {
#ifdef HAVE_OPENVDB
        nbt_vdb_grid v;
        if (nbt_vdb_read(o->density, o->grid_name, (size_t)1 << 28 /* 1 GiB of float */, &v, err, sizeof err) != 0)
            die_usage("--density: %s", err);
        g = nbt_grid_alloc(v.nx, v.ny, v.nz, v.origin, v.voxel);
        if (!g)
            die("out of memory");
        memcpy(g->data, v.data, v.nx * v.ny * v.nz * sizeof *g->data);
        nbt_vdb_grid_free(&v);
#else
        die_usage("--density: '%s' is an OpenVDB file, and this build has no OpenVDB (install libopenvdb-dev "
                  "and re-run configure), or convert it to nbt's raw grid", o->density);
#endif
    } else if (nbt_grid_read_raw(o->density, &g, err, sizeof err) != NBT_OK)
        die_usage("--density: %s", err);
    return g;
}

/* per-pixel kernels through the grid; the grid must hold the camera and every visible surface */
static nbt_screen_pixkern *medium_kernels(const opts *o, const nbt_grid *g, const nbt_screen_input *in,
                                          const nbt_beam_medium *m)
{
    nbt_camera cam;
    double lo[3], hi[3], slack = 1e-9 * g->voxel;
    for (int a = 0; a < 3; a++) {
        cam.pos[a] = o->cam[a];
        cam.fwd[a] = o->look[a] - o->cam[a];
        cam.up[a] = o->up[a];
    }
    double cr[3] = {cam.fwd[1] * cam.up[2] - cam.fwd[2] * cam.up[1], cam.fwd[2] * cam.up[0] - cam.fwd[0] * cam.up[2],
                    cam.fwd[0] * cam.up[1] - cam.fwd[1] * cam.up[0]};
    if (!(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2] > 0))
        die_usage("--look-at/--up: the view direction must be non-zero and not parallel to up");
    nbt_grid_box(g, lo, hi);
    for (int a = 0; a < 3; a++)
        if (!(o->cam[a] >= lo[a] - slack && o->cam[a] <= hi[a] + slack))
            die_usage("--density: the grid's box [%g,%g]x[%g,%g]x[%g,%g] does not hold the camera (%g,%g,%g): it must "
                      "cover the view (zero density where the air is clear)", lo[0], hi[0], lo[1], hi[1], lo[2], hi[2],
                      o->cam[0], o->cam[1], o->cam[2]);
    size_t np = in->w * in->h;
    float *skyD = malloc(np * sizeof *skyD);
    nbt_screen_pixkern *pix = malloc(np * sizeof *pix);
    if (!skyD || !pix)
        die("out of memory");
    for (size_t y = 0; y < in->h; y++)
        for (size_t x = 0; x < in->w; x++) {
            size_t i = y * in->w + x;
            double dir[3];
            nbt_camera_ray(&cam, in->w, in->h, in->dtheta, x, y, dir);
            skyD[i] = (float)nbt_grid_exit(g, cam.pos, dir);
            if (in->D[i] >= NBT_SCREEN_SKY)
                continue;
            for (int a = 0; a < 3; a++) {
                double p = cam.pos[a] + in->D[i] * dir[a];
                if (!(p >= lo[a] - slack && p <= hi[a] + slack))
                    die_usage("--density: the grid's box [%g,%g]x[%g,%g]x[%g,%g] does not hold the surface seen in "
                              "pixel (%zu, %zu) at distance %g: it must cover the view", lo[0], hi[0], lo[1], hi[1],
                              lo[2], hi[2], x, y, (double)in->D[i]);
            }
        }
    double step = o->step > 0 ? o->step : 0.5 * g->voxel, err;
    if (nbt_screen_medium_kernels(in, m, nbt_grid_density, (void *)g, &cam, step, skyD, (unsigned)o->threads, pix,
                                  &err) != NBT_OK)
        die("the per-pixel kernels could not be computed");
    fprintf(stderr, "nbt-scatter: per-pixel kernels through %s (%zux%zux%zu voxels of %g), step %g: max relative "
                    "change of M0, M2 on halving the step %.2g\n",
            o->density, g->nx, g->ny, g->nz, g->voxel, step, err);
    free(skyD);
    return pix;
}

#ifdef HAVE_GL
/* a GL method: per-pixel kernels from the CPU, the passes on the GPU */
static void run_gl(const opts *o, const nbt_screen_input *in, const nbt_screen_kernel *k,
                   const nbt_beam_medium *m, double *S, double *T, double *gpu_ms)
{
    size_t np = in->w * in->h;
    float *M0 = malloc(np * sizeof *M0), *beta = malloc(np * sizeof *beta), *sig = NULL, *Sf = malloc(np * 3 * sizeof *Sf);
    if (!M0 || !beta || !Sf)
        die("out of memory");
    nbt_screen_kernel *ke = NULL;
    if (o->gl_method == NBT_GLS_ELEK) {
        if (in->pix)
            die_usage("--method elek: Elek's W(s) is for homogeneous media; use --method shinya, naive or ref-a");
        ke = nbt_screen_kernel_alloc(NBT_SKERNEL_ELEK, m, NULL);
        sig = malloc(np * sizeof *sig);
        if (!ke || !sig)
            die("out of memory");
    }
    for (size_t i = 0; i < np; i++) {
        nbt_screen_kern kn;
        if (in->pix) {
            T[i] = in->pix[i].T, M0[i] = (float)in->pix[i].M0, beta[i] = (float)in->pix[i].beta_px;
            continue;
        }
        if (nbt_screen_kernel_eval(k, in->D[i], &kn) != NBT_OK)
            die("the kernel at pixel %zu could not be evaluated", i);
        double px = in->D[i] * in->dtheta;
        T[i] = kn.T, M0[i] = kn.n ? (float)kn.mass[0] : 0.0f, beta[i] = kn.n ? (float)(kn.scale[0] / px) : 0.0f;
        if (ke) {
            if (nbt_screen_kernel_eval(ke, in->D[i], &kn) != NBT_OK)
                die("the Elek kernel at pixel %zu could not be evaluated", i);
            sig[i] = kn.n ? (float)(kn.scale[0] / px) : 0.0f;
        }
    }
    char err[4096];
    if (egl_headless_open(err, sizeof err))
        die("--method %s needs OpenGL 4.3 through EGL: %s", o->method_name, err);
    nbt_gls_input gi = {in->w, in->h, in->rgb, in->D, M0, beta, sig, in->dtheta, o->cut, o->eps};
    nbt_status st = nbt_gls_run((nbt_gls_method)o->gl_method, &gi, Sf, gpu_ms);
    egl_headless_close();
    if (st != NBT_OK)
        die("--method %s failed on GL: %s", o->method_name, nbt_strerror(st));
    for (size_t i = 0; i < np * 3; i++)
        S[i] = Sf[i];
    nbt_screen_kernel_free(ke);
    free(M0);
    free(beta);
    free(sig);
    free(Sf);
}
#endif

static const char *kernel_label(const opts *o)
{
#ifdef HAVE_GL
    if (o->method == 2 && o->gl_method == NBT_GLS_ELEK)
        return "elek";
#endif
    return nbt_skernel_name((nbt_skernel_kind)o->kernel);
}

static void on_error(const char *reason, nbt_status st)
{
    (void)st;
    fprintf(stderr, "nbt-scatter: %s\n", reason);
}

int main(int argc, char **argv)
{
    cli_prog = "nbt-scatter";
    if (argc >= 2 && !strcmp(argv[1], "--version")) {
        printf("nbt-scatter (nbt) %s\n", nbt_version());
        return 0;
    }
    if (argc >= 2 && !strcmp(argv[1], "scene"))
        return cmd_scene(argc - 1, argv + 1);
    opts o;
    parse(argc, argv, &o);
    check_writable("-o", o.out);

    char err[512];
    nbt_image *im = NULL, *ref = NULL;
    nbt_status st = nbt_image_read_exr(o.in, &im, err, sizeof err);
    if (st != NBT_OK)
        die_usage("%s", err);
    if (!im->z)
        die_usage("%s: no depth channel Z: nbt-scatter needs R, G, B and Z (Blender: enable the Z pass)", o.in);
    if (o.compare) {
        if (nbt_image_read_exr(o.compare, &ref, err, sizeof err) != NBT_OK)
            die_usage("--compare: %s", err);
        if (ref->w != im->w || ref->h != im->h)
            die_usage("--compare: %s is %zux%zu, the input %zux%zu", o.compare, ref->w, ref->h, im->w, im->h);
    }
    nbt_kernel_correction corr;
    if (o.corr_path && nbt_kernel_correction_read(o.corr_path, &corr, err, sizeof err) != NBT_OK)
        die_usage("--correction: %s", err);
    nbt_grid *grid = o.density ? load_grid(&o) : NULL;

    nbt_set_error_handler(on_error); /* file errors above come back in err */
    double dtheta = 2.0 * tan(o.fov * M_PI / 360.0) / (double)im->h;
    float *D = ray_distances(&o, im, dtheta);
    nbt_beam_medium m = nbt_beam_homogeneous(o.sigma_t, o.albedo, o.B);
    nbt_screen_kernel *k = nbt_screen_kernel_alloc((nbt_skernel_kind)o.kernel, &m, o.corr_path ? &corr : NULL);
    if (!k)
        die("the kernel could not be set up");
    size_t np = im->w * im->h;
    double *S = malloc(np * 3 * sizeof *S), *T = malloc(np * sizeof *T);
    if (!S || !T)
        die("out of memory");
    nbt_screen_input in = {im->w, im->h, im->rgb, D, dtheta, NULL};
    nbt_screen_rule rule = o.method ? NBT_SCREEN_SOURCE : NBT_SCREEN_NEAR;
    double t0 = now();
    const char *how = "layered FFT";
    nbt_screen_pixkern *pix = grid ? medium_kernels(&o, grid, &in, &m) : NULL;
    in.pix = pix;
    char qhow[64];
    double gpu_ms = -1;
    if (o.method == 2) {
#ifdef HAVE_GL
        run_gl(&o, &in, k, &m, S, T, &gpu_ms);
        snprintf(qhow, sizeof qhow, "GL (%.3f ms GPU time)", gpu_ms);
        how = qhow;
#endif
    } else if (o.quantize) {
        float *Dq = malloc(np * sizeof *Dq);
        if (!Dq)
            die("out of memory");
        nbt_screen_quantize(D, np, (size_t)o.quantize, Dq);
        in.D = Dq;
        st = nbt_screen_layered(&in, k, rule, o.tail, (size_t)o.quantize + 2 /* sky, D = 0 */, (unsigned)o.threads,
                                S, NULL);
        in.D = D;
        free(Dq);
        for (size_t i = 0; i < np && st == NBT_OK; i++) { /* the direct part at the true distance */
            nbt_screen_kern kn;
            st = nbt_screen_kernel_eval(k, D[i], &kn);
            T[i] = kn.T;
        }
        snprintf(qhow, sizeof qhow, "layered FFT on %ld quantised layers (approximate)", o.quantize);
        how = qhow;
    } else {
        /* the FFT is exact when the distances form few layers; it says EDOM otherwise */
        nbt_set_error_handler(NULL);
        st = o.layers > 0 && !pix
                 ? nbt_screen_layered(&in, k, rule, o.tail, (size_t)o.layers, (unsigned)o.threads, S, T)
                 : NBT_EDOM;
        nbt_set_error_handler(on_error);
        if (st == NBT_EDOM) {
            how = "brute force";
            st = nbt_screen_brute(&in, k, rule, o.tail, (unsigned)o.threads, S, T);
        }
    }
    if (st != NBT_OK)
        die("scattering failed: %s", nbt_strerror(st));
    double t1 = now();
    fprintf(stderr, "nbt-scatter: %s (%s, %s kernel) by %s, %zux%zu: %.3f s\n", o.method_name,
            o.method == 1 ? "operator B" : o.method == 0 ? "operator A" : "approximating operator A",
            kernel_label(&o), how, im->w, im->h, t1 - t0);

    if (ref) {
        double *Sr = malloc(np * 3 * sizeof *Sr);
        if (!Sr)
            die("out of memory");
        for (size_t i = 0; i < np * 3; i++)
            Sr[i] = (double)ref->rgb[i] - T[i / 3] * (double)im->rgb[i];
        nbt_screen_metrics mt;
        if (nbt_screen_compare(&in, k, S, Sr, &mt) != NBT_OK)
            die("comparison failed");
        printf("relL1 %.6g relRMS %.6g edge %.6g bias %.6g max %.6g\n", mt.rel_l1, mt.rel_rms, mt.edge, mt.bias,
               mt.max);
        free(Sr);
    }
    /* the whole image: direct plus scattered */
    nbt_image *out = nbt_image_alloc(im->w, im->h, 1);
    if (!out)
        die("out of memory");
    for (size_t i = 0; i < np * 3; i++)
        out->rgb[i] = (float)(T[i / 3] * im->rgb[i] + S[i]);
    memcpy(out->z, im->z, np * sizeof *out->z);
    char sst[32], ssa[32], sb[32], sfov[32];
    snprintf(sst, sizeof sst, "%.17g", o.sigma_t);
    snprintf(ssa, sizeof ssa, "%.17g", o.albedo);
    snprintf(sb, sizeof sb, "%.17g", o.B);
    snprintf(sfov, sizeof sfov, "%.17g", o.fov);
    const char *attrs[] = {"nbt.method", o.method_name, "nbt.kernel", kernel_label(&o), "nbt.sigma_t", sst, "nbt.albedo", ssa, "nbt.B",
                           sb, "nbt.fov_y", sfov, "nbt.depth", o.ray_depth ? "ray" : "plane", "nbt.version",
                           nbt_version()};
    /* preview first, so that a failed EXR write can take it back: all or nothing */
    char *png = o.png ? png_path(o.out) : NULL;
    if (png && scatter_preview_png(out, png) != 0)
        die("cannot write the preview '%s'", png);
    if (nbt_image_write_exr(out, o.out, attrs, sizeof attrs / sizeof attrs[0] / 2, err, sizeof err) != NBT_OK) {
        if (png)
            unlink(png);
        die("%s", err);
    }
    free(png);
    nbt_image_free(out);
    nbt_image_free(im);
    nbt_image_free(ref);
    nbt_screen_kernel_free(k);
    nbt_grid_free(grid);
    free(pix);
    free(D);
    free(S);
    free(T);
    return 0;
}
