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
#include <sys/stat.h>
#include <nbt/nbt.h>
#include <nbt/image.h>
#include <nbt/screen_path.h>
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
    puts("Usage: nbt-scatter IN.exr -o OUT.exr --fov-y DEG --sigma-t X --albedo A (--phase SPEC | --B B | --dtheta DEG)\n"
         "                   [options]\n"
         "       nbt-scatter scene NAME -o IN.exr [--size WxH] [--overscan F]\n"
         "       nbt-scatter --version\n\n"
         "Applies multiple scattering in a homogeneous medium to a render. IN.exr holds R, G, B and Z as\n"
         "Blender writes it: planar depth along the view axis, sky at Z >= 1e10 (or inf). A render with\n"
         "overscan (data window larger than the display window) lends the light of its border: the\n"
         "operators run on the whole data window and OUT.exr holds the display window. OUT.exr gets\n"
         "R, G, B = T c + S (direct plus scattered) where the input had them, Z, the input's other\n"
         "channels and header attributes, and layers S (scattered), T (transmittance per channel) and\n"
         "offscreen.X (the fraction of each pixel's kernel outside the data window); OUT.png a\n"
         "tone-mapped preview.\n\n"
         "  -o, --output OUT.exr   output (required; must end in .exr and differ from the input)\n"
         "  --fov-y DEG            vertical field of view of the display window, (0, 180) (Blender: the\n"
         "                         camera's vertical angle, see doc/screenspace.md for sensor fit)\n"
         "  --display-window X0,Y0,X1,Y1\n"
         "                         the frame (EXR pixel coordinates, inclusive) inside a render that was made\n"
         "                         larger for overscan but has no display window of its own\n"
         "  --sigma-t X|R,G,B      extinction coefficient per scene unit, > 0, one or per channel\n"
         "  --albedo A|R,G,B       single-scattering albedo, [0, 1], one or per channel\n"
         "  --phase SPEC           the phase function, as in nbt-gen: hg:g=G, hg2:g1=,g2=,w=, gauss:B=B,\n"
         "                         sog:FILE, table:FILE; give it three times for one per channel (R, G, B)\n"
         "  --B B | --dtheta DEG   a Gaussian phase of width B > 0 (or dtheta in (0, 90], dtheta^2 = 4B) for\n"
         "                         the narrow-beam kernels (moment, smallangle, corrected, single, lineint)\n"
         "  --kernel K             with --phase: fitted (default: the first order exact for the phase, the\n"
         "                         higher orders from the fitted model; shipped for HG, g in [0, 0.95]),\n"
         "                         first (single scattering only), elek (Elek et al.'s Gaussian carrying the\n"
         "                         fitted kernel's mass). With --B: moment (default for ref-a), smallangle,\n"
         "                         single, lineint, elek (default for ref-b), corrected (--correction FILE)\n"
         "  --model FILE           the higher-order model for --kernel fitted (nbt-fit screenmodel), for\n"
         "                         phases outside the shipped HG model\n"
         "  --geometry G           inside (default: the camera in the medium) or entering (the medium begins\n"
         "                         at the camera, vacuum behind it)\n"
         "  --method M             ref-a: operator A, every pixel pair through the nearer pixel's kernel\n"
         "                         (Shinya et al., corrected; the default with --phase); ref-b: operator B,\n"
         "                         every source its own kernel (Elek et al.'s rule). Both exact on the CPU.\n"
         "                         path: a path-traced reference of the world the image describes (each\n"
         "                         pixel a Lambertian emitter square at its depth, the camera inside the\n"
         "                         medium), independent of the kernels; writes the standard error of S as\n"
         "                         layer Sse. On GL (4.3 compute, Mesa's llvmpipe without a GPU), for --B:\n"
         "                         nbt (operator A from fitted pyramid weights; the default in builds with\n"
         "                         GL), shinya (windowed), shinya-literal (Alg. 1-4 as printed), naive (one\n"
         "                         pyramid read), elek (Elek et al.; also with --phase)\n"
         "  --spp N                path: samples per pixel (per pass with --noise; default 64)\n"
         "  --noise X              path: add passes until the 4x4-binned relative noise of S is below X\n"
         "  --seed S               path: the random seed (1); the result depends on it, not on --threads\n"
         "  --cut C                shinya: window radius in beta (3)\n"
         "  --eps E                elek: smoothstep width of the level masks (0.1)\n"
         "  --depth plane|ray      what Z holds: planar depth (default) or distance along the ray\n"
         "  --layers N             use the exact layered FFT when Z takes at most N distinct values\n"
         "                         (default 64), else brute force; --layers 0 forces brute force\n"
         "  --quantize L           approximate: snap the ray distances to L log-spaced layers and use the FFT\n"
         "                         (T stays exact); measure the error against brute force with --compare.\n"
         "                         Default with --phase: 64 when the depth has more than --layers values\n"
         "                         (continuous depth); 0: never (exact, brute force)\n"
         "  --extend F             ref-a, ref-b: beyond the data window, continue it as its mirror image\n"
         "                         (colour and depth; lamps capped at 4x the border's median) for F times\n"
         "                         the frame's larger side (default 0.25; 0: nothing beyond sends light)\n"
         "  --tail X               truncate each kernel where less than X of its mass lies outside (1e-7)\n"
         "  --threads N            0 = all cores (default)\n"
         "  --compare REF.exr      print 'relL1 X relRMS X edge X bias X max X binned4 X halo X' for the\n"
         "                         scattered part (binned4: 4x4 bins; halo: the bins within 12 px of a lamp)\n"
         "                         against REF.exr, an nbt-scatter output (e.g. --method path) for the\n"
         "                         same input, camera and medium (checked from its nbt.* attributes; a\n"
         "                         different phase is allowed, with a note, to measure an approximation)\n"
         "  --no-png               no preview\n"
         "  --density FILE         heterogeneous medium: a density grid (.raw: nbt's raw grid; .vdb: OpenVDB,\n"
         "                         the float grid 'density' or --grid NAME) scaling sigma_t; per-pixel kernels\n"
         "                         from eq. 28/29 along each view ray (ref-a, moment kernel). The grid's box\n"
         "                         must hold the camera and every visible surface.\n"
         "  --camera X,Y,Z --look-at X,Y,Z --up X,Y,Z\n"
         "                         the camera in the grid's world (default 0,0,0 looking at 0,0,-1, up 0,1,0)\n"
         "  --step S               ray-march step in world units (default half a voxel)\n"
         "                         (--grid, --camera, --look-at, --up, --step: with --density only)\n\n"
         "'scene NAME' writes a generated test render: plane, step, layers, slant, blocks, lamps (a wall\n"
         "with HDR lamps, two just outside the frame); --size WxH of the frame (default 320x240),\n"
         "--overscan F adds F times the width and height on each side as a data window beyond the\n"
         "display window. Exit status: 0 success, 1 failure, 2 bad usage.");
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
    if (n > 4 && !strcmp(out + n - 4, ".exr"))
        p[n - 4] = '\0';
    strcat(p, ".png");
    return p;
}

static int cmd_scene(int argc, char **argv)
{
    const char *out = NULL;
    size_t w = 320, h = 240;
    double over = 0;
    static const struct option lo[] = {{"output", 1, 0, 'o'}, {"size", 1, 0, 's'}, {"overscan", 1, 0, 'v'},
                                       {"help", 0, 0, 'h'}, {0, 0, 0, 0}};
    int c;
    while ((c = getopt_long(argc, argv, ":o:h", lo, NULL)) != -1) {
        if (c == 'o')
            out = optarg;
        else if (c == 's')
            parse_size(optarg, &w, &h);
        else if (c == 'v')
            over = opt_double("--overscan", optarg, 0, 0, 1, 0);
        else if (c == 'h') {
            help();
            return 0;
        } else
            die_bad_option(c, argv, "nbt-scatter");
    }
    if (optind + 1 != argc)
        die_usage("scene: name one scene: %s", scene_names());
    int kind = scene_parse(argv[optind]);
    if (kind < 0)
        die_usage("scene: '%s' is not accepted: expected one of %s", argv[optind], scene_names());
    if (!out)
        die_usage("scene: -o OUT.exr is required");
    check_writable("-o", out);
    nbt_image *im = scene_make(kind, w, h, (size_t)lround(over * (double)w), (size_t)lround(over * (double)h));
    if (!im)
        die("out of memory");
    char err[512];
    if (nbt_image_write_exr_ex(im, out, NULL, err, sizeof err) != NBT_OK)
        die("%s", err);
    nbt_image_free(im);
    return 0;
}

typedef struct {
    const char *in, *out, *compare, *corr_path, *density, *grid_name, *model_path;
    const char *grid_opt; /* the first of --camera, --look-at, --up, --grid, --step given: only with --density */
    double fov, tail, step, noise, extend;
    scatter_medium med;
    long spp;
    unsigned long long seed;
    double cam[3], look[3], up[3];
    int method; /* 0: ref-a, 1: ref-b, 2: a GL method, 3: path */
    int gl_method;
    double cut, eps;
    const char *method_name;
    int kernel; /* -1: the method's default */
    int disp_given;
    nbt_box2i disp; /* --display-window: the frame inside a render that has no display window of its own */
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
           O_NOPNG, O_CORR, O_DENS, O_GRID, O_CAM, O_LOOK, O_UP, O_STEP, O_QUANT, O_CUT, O_EPS, O_PHASE, O_MODEL,
           O_GEO, O_SPP, O_NOISE, O_SEED, O_DISP, O_EXT };
    static const struct option lo[] = {
        {"output", 1, 0, 'o'},    {"fov-y", 1, 0, O_FOV},     {"sigma-t", 1, 0, O_ST},    {"albedo", 1, 0, O_ALB},
        {"B", 1, 0, O_B},         {"dtheta", 1, 0, O_DTH},    {"method", 1, 0, O_METHOD}, {"kernel", 1, 0, O_KERNEL},
        {"depth", 1, 0, O_DEPTH}, {"layers", 1, 0, O_LAYERS}, {"tail", 1, 0, O_TAIL},     {"threads", 1, 0, O_THREADS},
        {"compare", 1, 0, O_CMP}, {"no-png", 0, 0, O_NOPNG},  {"correction", 1, 0, O_CORR}, {"help", 0, 0, 'h'},
        {"density", 1, 0, O_DENS},  {"grid", 1, 0, O_GRID},     {"camera", 1, 0, O_CAM},    {"look-at", 1, 0, O_LOOK},
        {"up", 1, 0, O_UP},         {"step", 1, 0, O_STEP},     {"quantize", 1, 0, O_QUANT},
        {"cut", 1, 0, O_CUT},       {"eps", 1, 0, O_EPS},       {"phase", 1, 0, O_PHASE},   {"model", 1, 0, O_MODEL},
        {"geometry", 1, 0, O_GEO},  {"spp", 1, 0, O_SPP},       {"noise", 1, 0, O_NOISE},   {"seed", 1, 0, O_SEED},
        {"display-window", 1, 0, O_DISP}, {"extend", 1, 0, O_EXT},
        {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->fov = o->med.B = NAN;
    o->tail = 1e-7;
    o->kernel = -1;
    o->png = 1;
    o->seed = 1;
    o->extend = -1;
    o->quantize = -1; /* auto: exact when the depths form few layers; else 64 layers for --phase, brute force for --B */
    int method_given = 0;
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
    while ((c = getopt_long(argc, argv, ":o:h", lo, NULL)) != -1) {
        switch (c) {
        case 'o': o->out = optarg; break;
        case O_FOV: o->fov = opt_double("--fov-y", optarg, 0, 1, 180, 1); break;
        case O_ST: o->med.nst = parse_triple("--sigma-t", optarg, 0, 1, 1e6, o->med.sigma_t); break;
        case O_ALB: o->med.nalb = parse_triple("--albedo", optarg, 0, 0, 1, o->med.albedo); break;
        case O_B:
            if (!isnan(o->med.B))
                die_usage("--B and --dtheta: give one phase width");
            o->med.B = opt_double("--B", optarg, 0, 1, 1, 0);
            break;
        case O_DTH: {
            if (!isnan(o->med.B))
                die_usage("--B and --dtheta: give one phase width");
            double d = opt_double("--dtheta", optarg, 0, 1, 90, 0) * M_PI / 180.0;
            o->med.B = d * d / 4.0;
            break;
        }
        case O_PHASE: medium_add_phase(&o->med, optarg); break;
        case O_MODEL: o->model_path = optarg; break;
        case O_GEO:
            if (strcmp(optarg, "inside") && strcmp(optarg, "entering"))
                die_usage("--geometry: '%s' is not accepted: expected inside (the camera in the medium) or entering "
                          "(the medium begins at the camera)", optarg);
            o->med.geometry = !strcmp(optarg, "entering") ? NBT_SCREEN_ENTERING : NBT_SCREEN_INSIDE;
            break;
        case O_SPP: o->spp = opt_long("--spp", optarg, 1, 1L << 30); break;
        case O_NOISE: o->noise = opt_double("--noise", optarg, 0, 1, 1, 1); break;
        case O_EXT: o->extend = opt_double("--extend", optarg, 0, 0, 4, 0); break;
        case O_SEED: o->seed = (unsigned long long)opt_long("--seed", optarg, 0, 0x7fffffffL); break;
        case O_DISP: {
            long v[4];
            char *end;
            const char *p = optarg;
            for (int i = 0; i < 4; i++) {
                errno = 0;
                v[i] = strtol(p, &end, 10);
                if (end == p || errno || *end != (i < 3 ? ',' : '\0') || labs(v[i]) > (1L << 30))
                    die_usage("--display-window: '%s' is not accepted: expected X0,Y0,X1,Y1 (integers, EXR pixel "
                              "coordinates, inclusive)", optarg);
                p = end + 1;
            }
            if (v[2] < v[0] || v[3] < v[1])
                die_usage("--display-window: '%s' is not accepted: X1 >= X0 and Y1 >= Y0", optarg);
            o->disp_given = 1;
            o->disp = (nbt_box2i){(int32_t)v[0], (int32_t)v[1], (int32_t)v[2], (int32_t)v[3]};
            break;
        }
        case O_METHOD:
            method_given = 1;
            o->method_name = optarg;
            if (!strcmp(optarg, "ref-a"))
                o->method = 0;
            else if (!strcmp(optarg, "ref-b"))
                o->method = 1;
            else if (!strcmp(optarg, "path"))
                o->method = 3;
            else {
#ifdef HAVE_GL
                nbt_gls_method gm;
                if (nbt_gls_method_parse(optarg, &gm) != NBT_OK)
                    die_usage("--method: '%s' is not accepted: expected ref-a, ref-b, path or a GL method (%s)", optarg,
                              gl_method_names());
                o->method = 2;
                o->gl_method = (int)gm;
#else
                die_usage("--method: '%s' is not accepted: expected ref-a, ref-b or path (this build has no GL)",
                          optarg);
#endif
            }
            break;
        case O_KERNEL:
            if (nbt_skernel_parse(optarg, &kk) != NBT_OK)
                die_usage("--kernel: '%s' is not accepted: expected fitted, first, moment, smallangle, corrected, "
                          "single, lineint or elek", optarg);
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
        case O_GRID: o->grid_name = optarg; o->grid_opt = o->grid_opt ? o->grid_opt : "--grid"; break;
        case O_CAM: parse_vec3("--camera", optarg, o->cam); o->grid_opt = o->grid_opt ? o->grid_opt : "--camera"; break;
        case O_LOOK: parse_vec3("--look-at", optarg, o->look); o->grid_opt = o->grid_opt ? o->grid_opt : "--look-at"; break;
        case O_UP: parse_vec3("--up", optarg, o->up); o->grid_opt = o->grid_opt ? o->grid_opt : "--up"; break;
        case O_STEP:
            o->step = opt_double("--step", optarg, 0, 1, 1e30, 0);
            o->grid_opt = o->grid_opt ? o->grid_opt : "--step";
            break;
        case O_QUANT:
            o->quantize = opt_long("--quantize", optarg, 0, 4096);
            if (o->quantize == 1)
                die_usage("--quantize: '1' is not accepted: expected 0 (exact: brute force when needed) or 2..4096");
            break;
        case O_CUT: o->cut = opt_double("--cut", optarg, 0, 1, 100, 0); break;
        case O_EPS: o->eps = opt_double("--eps", optarg, 0, 0, 100, 0); break;
        case 'h': help(); exit(0);
        default: die_bad_option(c, argv, "nbt-scatter");
        }
    }
    if (optind + 1 != argc)
        die_usage("name one input render IN.exr (see 'nbt-scatter --help')");
    o->in = argv[optind];
    if (!o->out)
        die_usage("-o OUT.exr is required");
    size_t no = strlen(o->out);
    if (no < 5 || strcmp(o->out + no - 4, ".exr"))
        die_usage("-o: '%s' is not accepted: the output is OpenEXR and its name must end in .exr (the preview "
                  "gets .png beside it)", o->out);
    if (isnan(o->fov))
        die_usage("--fov-y DEG is required: the vertical field of view in (0, 180)");
    if (!o->med.nst)
        die_usage("--sigma-t X is required: the extinction coefficient, > 0 (or R,G,B)");
    if (!o->med.nalb)
        die_usage("--albedo A is required: in [0, 1] (or R,G,B)");
    medium_finish(&o->med);
    int phase = o->med.nphase > 0;
    if (phase == !isnan(o->med.B))
        die_usage(phase ? "--phase and --B/--dtheta: give one phase"
                        : "--phase SPEC (e.g. hg:g=0.9) or --B B / --dtheta DEG (a Gaussian phase) is required");
    if (phase && !method_given && o->method == 2) { /* the GL methods take erfc kernels of a Gaussian phase */
        o->method = 0;
        o->method_name = "ref-a";
    }
    if (o->kernel < 0)
        o->kernel = phase ? NBT_SKERNEL_FITTED : o->method == 1 ? NBT_SKERNEL_ELEK : NBT_SKERNEL_MOMENT;
    if (phase && o->kernel != NBT_SKERNEL_FITTED && o->kernel != NBT_SKERNEL_FIRST && o->kernel != NBT_SKERNEL_ELEK)
        die_usage("--kernel %s: with --phase the kernels are fitted (default), first or elek; %s is for a Gaussian "
                  "phase (--B or --dtheta)", nbt_skernel_name((nbt_skernel_kind)o->kernel),
                  nbt_skernel_name((nbt_skernel_kind)o->kernel));
    if (!phase && (o->kernel == NBT_SKERNEL_FITTED || o->kernel == NBT_SKERNEL_FIRST))
        die_usage("--kernel %s needs --phase SPEC (for a Gaussian phase: --phase gauss:B=B)",
                  nbt_skernel_name((nbt_skernel_kind)o->kernel));
    if (o->model_path && (!phase || o->kernel == NBT_SKERNEL_FIRST))
        die_usage("--model: a fitted model serves --phase with --kernel fitted or elek");
    if (o->method == 2 && o->gl_method == NBT_GLS_ELEK && phase)
        o->kernel = NBT_SKERNEL_ELEK;
    if (o->method == 2 && phase && o->gl_method != NBT_GLS_ELEK && o->kernel == NBT_SKERNEL_ELEK)
        die_usage("--kernel elek: elek's Gaussian comes with --method elek");
    if (o->method == 2 && !phase && (o->kernel == NBT_SKERNEL_LINEINT || o->kernel == NBT_SKERNEL_ELEK ||
                                     o->kernel == NBT_SKERNEL_SINGLE))
        die_usage("--kernel %s: the GL methods take one erfc kernel per pixel (moment, smallangle, corrected); "
                  "elek's Gaussian comes with --method elek", nbt_skernel_name((nbt_skernel_kind)o->kernel));
    if (o->method == 2 && medium_channels(&o->med) == 3)
        die_usage("--method %s: the GL methods take one medium for all channels; an RGB medium needs ref-a, ref-b "
                  "or path", o->method_name);
    if (o->method == 2 && o->quantize > 0)
        die_usage("--quantize belongs to the CPU references");
    if (o->method == 3 && (o->quantize >= 0 || o->density || o->compare))
        die_usage("--method path: --quantize, --density and --compare belong to the screen-space methods (compare "
                  "their outputs with a path-traced one: run the method with --compare PATH.exr)");
    if (o->method != 3 && (o->spp || o->noise > 0))
        die_usage("--spp and --noise belong to --method path");
    if (o->density && (phase || medium_channels(&o->med) == 3))
        die_usage("--density: heterogeneous media take a Gaussian phase (--B) and one medium for all channels");
    if (o->density && o->quantize > 0)
        die_usage("--quantize and --density: per-pixel kernels have no layers to quantise");
    if (o->density && (o->method == 1 || o->kernel != NBT_SKERNEL_MOMENT))
        die_usage("--density: heterogeneous media use operator A with the moment kernel (eq. 28/29): "
                  "--method ref-a or a GL method, --kernel moment");
    if (o->density && o->method == 2 && o->gl_method == NBT_GLS_ELEK)
        die_usage("--method elek: Elek's W(s) is for homogeneous media, not --density; use --method shinya, naive or "
                  "ref-a");
    if (o->grid_opt && !o->density)
        die_usage("%s places or marches a --density grid; without --density it would be ignored", o->grid_opt);
    if (o->density) { /* the camera of the ray march: checked before the input and the grid are read */
        double f[3] = {o->look[0] - o->cam[0], o->look[1] - o->cam[1], o->look[2] - o->cam[2]};
        double cr[3] = {f[1] * o->up[2] - f[2] * o->up[1], f[2] * o->up[0] - f[0] * o->up[2],
                        f[0] * o->up[1] - f[1] * o->up[0]};
        if (!(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2] > 0))
            die_usage("--look-at %g,%g,%g from --camera %g,%g,%g: the view direction must be non-zero and not parallel "
                      "to --up %g,%g,%g", o->look[0], o->look[1], o->look[2], o->cam[0], o->cam[1], o->cam[2], o->up[0],
                      o->up[1], o->up[2]);
    }
    if ((o->kernel == NBT_SKERNEL_CORRECTED) != (o->corr_path != NULL))
        die_usage("--kernel corrected and --correction FILE go together");
    if (o->extend >= 0 && (o->method > 1 || o->density))
        die_usage("--extend belongs to ref-a and ref-b on a homogeneous medium");
    if (o->extend < 0)
        o->extend = o->method <= 1 && !o->density ? 0.25 : 0;
    if (o->method == 3 && !o->spp)
        o->spp = o->noise > 0 ? 16 : 64;
}

/* The frame: the display window inside the data window (overscan: the data
 * window is larger and the operators use all of it). */
typedef struct {
    size_t x0, y0, w, h; /* the display window in data-window pixels */
    double cx, cy;       /* the optical axis (the display window's centre) in data-window pixel coordinates */
} frame;

static frame frame_of(const opts *o, const nbt_image *im)
{
    const nbt_box2i *d = &im->display;
    long dx1 = (long)im->x0 + (long)im->w - 1, dy1 = (long)im->y0 + (long)im->h - 1;
    if (d->min_x < im->x0 || d->min_y < im->y0 || d->max_x > dx1 || d->max_y > dy1)
        die_usage("%s: the data window (%ld,%ld)-(%ld,%ld) does not contain the display window (%ld,%ld)-(%ld,%ld): "
                  "nbt-scatter needs every pixel of the frame (a border or region render cannot be fogged; with "
                  "overscan the data window is the larger one)", o->in, (long)im->x0, (long)im->y0, dx1, dy1,
                  (long)d->min_x, (long)d->min_y, (long)d->max_x, (long)d->max_y);
    frame f = {(size_t)(d->min_x - im->x0), (size_t)(d->min_y - im->y0), (size_t)(d->max_x - d->min_x + 1),
               (size_t)(d->max_y - d->min_y + 1), 0, 0};
    f.cx = (double)f.x0 + 0.5 * (double)f.w;
    f.cy = (double)f.y0 + 0.5 * (double)f.h;
    return f;
}

/* distance along the ray per unit planar depth at pixel (x, y) (may lie outside the data window) */
static double ray_factor(const frame *fr, double dtheta, long x, long y)
{
    double u = ((double)x + 0.5 - fr->cx) * dtheta, v = ((double)y + 0.5 - fr->cy) * dtheta;
    return sqrt(1.0 + u * u + v * v);
}

/* the render as the operators need it: distances along the ray, from the optical axis at (cx, cy) */
static float *ray_distances(const opts *o, const nbt_image *im, const frame *fr, double dtheta)
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
                D[i] = (float)(o->ray_depth ? Z : Z * ray_factor(fr, dtheta, (long)x, (long)y));
        }
    /* radiance: finite, and negative only by a pixel filter's ringing (a small fraction of the brightest) */
    double big = 0;
    for (size_t i = 0; i < 3 * np; i++) {
        if (!isfinite(im->rgb[i]))
            die_usage("%s: colour %g at pixel (%zu, %zu) channel %c: expected finite radiance", o->in,
                      (double)im->rgb[i], (i / 3) % im->w, (i / 3) / im->w, "RGB"[i % 3]);
        big = fmax(big, fabs((double)im->rgb[i]));
    }
    for (size_t i = 0; i < 3 * np; i++)
        if (im->rgb[i] < -0.01 * big)
            die_usage("%s: colour %g at pixel (%zu, %zu) channel %c: expected radiance >= 0 (small negative values "
                      "from a pixel filter, down to -1%% of the brightest value, are kept)", o->in, (double)im->rgb[i],
                      (i / 3) % im->w, (i / 3) / im->w, "RGB"[i % 3]);
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
    nbt_grid_box(g, lo, hi); /* the view direction was checked with the options */
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
#define GL_GROUPS 4
static void run_gl(const opts *o, const nbt_screen_input *in, const nbt_screen_kernel *k, double *S, double *T,
                   double *gpu_ms)
{
    size_t np = in->w * in->h;
    float *M0 = calloc(np * GL_GROUPS, sizeof *M0), *beta = calloc(np * GL_GROUPS, sizeof *beta), *sig = NULL,
          *Sf = malloc(np * 3 * sizeof *Sf);
    if (!M0 || !beta || !Sf)
        die("out of memory");
    /* elek: its Gaussian (mass and deviation) from the ELEK kernel (for a phase: k itself) */
    nbt_screen_kernel *ke = NULL;
    const nbt_screen_kernel *kel = NULL;
    if (o->gl_method == NBT_GLS_ELEK) { /* homogeneous only: --density refused with the options */
        kel = o->kernel == NBT_SKERNEL_ELEK ? k : (ke = medium_kernel(&o->med, NBT_SKERNEL_ELEK, NULL));
        sig = malloc(np * sizeof *sig);
        if (!sig)
            die("out of memory");
    }
    for (size_t i = 0; i < np; i++) {
        nbt_screen_kern kn;
        if (in->pix) {
            T[i] = in->pix[i].T, M0[i] = (float)in->pix[i].M0, beta[i] = (float)in->pix[i].beta_px;
            continue;
        }
        double px = in->D[i] * in->dtheta;
        if (kel) {
            if (nbt_screen_kernel_eval(kel, in->D[i], &kn) != NBT_OK)
                die("the Elek kernel at pixel %zu could not be evaluated", i);
            T[i] = kn.T, M0[i] = kn.n ? (float)kn.mass[0] : 0.0f, beta[i] = 0.0f;
            sig[i] = kn.n ? (float)(kn.scale[0] / px) : 0.0f;
            continue;
        }
        if (nbt_screen_kernel_eval(k, in->D[i], &kn) != NBT_OK)
            die("the kernel at pixel %zu could not be evaluated", i);
        T[i] = kn.T;
        /* a kernel of many atoms (built for a phase) becomes GL_GROUPS erfc kernels, one per band of scales
         * (relative to D: below 1/64, 1/8, 1, above), each with its band's mass and second moment */
        for (int g = 0; g < GL_GROUPS; g++) {
            double m = 0, r2 = 0;
            for (size_t a = 0; a < kn.n; a++) {
                double l = log2(kn.scale[a] / in->D[i]), s = kn.scale[a] / px;
                int ga = kn.n == 1 ? 0 : l < -6 ? 0 : l < -3 ? 1 : l < 0 ? 2 : 3;
                if (ga != g)
                    continue;
                m += kn.mass[a];
                r2 += kn.mass[a] * (kn.shape[a] == NBT_ATOM_ERFC ? 2.0 / 3.0 : 2.0) * s * s;
            }
            M0[(size_t)g * np + i] = (float)m;
            beta[(size_t)g * np + i] = m > 0 ? (float)sqrt(1.5 * r2 / m) : 0.0f; /* erfc: <r^2> = 2 beta^2/3 */
        }
    }
    char err[4096];
    if (egl_headless_open(err, sizeof err))
        die("--method %s needs OpenGL 4.3 through EGL: %s", o->method_name, err);
    int ng = kel || in->pix || nbt_screen_kernel_channels(k) != 1 ? 1 : GL_GROUPS;
    *gpu_ms = 0;
    for (size_t i = 0; i < np * 3; i++)
        S[i] = 0;
    for (int g = 0; g < ng; g++) {
        int used = 0;
        for (size_t i = 0; i < np && !used; i++)
            used = M0[(size_t)g * np + i] > 0;
        if (!used && g > 0)
            continue;
        double ms = 0;
        nbt_gls_input gi = {in->w, in->h, in->rgb, in->D, M0 + (size_t)g * np, beta + (size_t)g * np, sig,
                            in->dtheta, o->cut, o->eps};
        nbt_status st = nbt_gls_run((nbt_gls_method)o->gl_method, &gi, Sf, &ms);
        if (st != NBT_OK) {
            egl_headless_close();
            die("--method %s failed on GL: %s", o->method_name, nbt_strerror(st));
        }
        *gpu_ms += ms;
        for (size_t i = 0; i < np * 3; i++)
            S[i] += Sf[i];
    }
    egl_headless_close();
    nbt_screen_kernel_free(ke);
    free(M0);
    free(beta);
    free(sig);
    free(Sf);
}
#endif

/* What the method computes, for the status line: the GL gathers naive and
 * elek read at the receiver's width (elek: Elek et al.'s rule, operator B's
 * kernels); naive leaves sky receivers at 0 (no width to read at). */
static const char *method_goal(const opts *o)
{
    if (o->method == 3)
        return "the scene's world";
    if (o->method == 1)
        return "operator B";
    if (o->method == 0)
        return "operator A";
    if (!strcmp(o->method_name, "elek"))
        return "approximating operator B: a gather at the sources' blurred width";
    if (!strcmp(o->method_name, "naive"))
        return "a gather at each receiver's own width; sky receives nothing";
    if (!strcmp(o->method_name, "shinya-literal"))
        return "Shinya et al.'s Alg. 1-4 as printed";
    return "approximating operator A";
}

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

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* index x (any integer) reflected into [0, n): ..., 1, 0 | 0, 1, ..., n-1 | n-1, n-2, ... */
static size_t mirror(long x, size_t n)
{
    long p = 2 * (long)n, r = x % p;
    if (r < 0)
        r += p;
    return (size_t)(r < (long)n ? r : p - 1 - r);
}

/* FNV-1a over the frame's colours and depths: --compare refuses a reference made from another input */
static unsigned long long input_hash(const nbt_image *im, const frame *fr)
{
    unsigned long long h = 1469598103934665603ull;
    for (size_t y = fr->y0; y < fr->y0 + fr->h; y++)
        for (size_t x = fr->x0; x < fr->x0 + fr->w; x++) {
            size_t i = y * im->w + x;
            float v[4] = {im->rgb[3 * i], im->rgb[3 * i + 1], im->rgb[3 * i + 2], im->z[i]};
            const unsigned char *b = (const unsigned char *)v;
            for (size_t j = 0; j < sizeof v; j++)
                h = (h ^ b[j]) * 1099511628211ull;
        }
    return h;
}

/* the medium's and the input's nbt.* attributes, as written and as --compare checks them */
typedef struct {
    char st[96], alb[96], phase[3][128], phases[3 * 128 + 8], fov[32], hash[32];
} medium_attrs;

static void medium_attrs_fill(const opts *o, unsigned long long hash, medium_attrs *a)
{
    medium_triple_str(o->med.sigma_t, o->med.nst, a->st, sizeof a->st);
    medium_triple_str(o->med.albedo, o->med.nalb, a->alb, sizeof a->alb);
    for (int c = 0; c < 3; c++) {
        if (o->med.nphase)
            snprintf(a->phase[c], sizeof a->phase[c], "%s", nbt_phase_name(medium_phase(&o->med, c)));
        else
            snprintf(a->phase[c], sizeof a->phase[c], "gauss:B=%.17g", o->med.B);
    }
    if (strcmp(a->phase[0], a->phase[1]) || strcmp(a->phase[0], a->phase[2]))
        snprintf(a->phases, sizeof a->phases, "%s;%s;%s", a->phase[0], a->phase[1], a->phase[2]);
    else
        snprintf(a->phases, sizeof a->phases, "%s", a->phase[0]);
    snprintf(a->fov, sizeof a->fov, "%.17g", o->fov);
    snprintf(a->hash, sizeof a->hash, "%016llx", hash);
}

/* --compare: the reference must be for the same input, medium and camera */
static void check_reference(const opts *o, const nbt_image *ref, const medium_attrs *a)
{
    const char *names[] = {"nbt.sigma_t", "nbt.albedo", "nbt.phase", "nbt.fov_y", "nbt.geometry", "nbt.input"};
    const char *want[] = {a->st, a->alb, a->phases, a->fov,
                          o->med.geometry == NBT_SCREEN_ENTERING ? "entering" : "inside", a->hash};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        const char *v = nbt_image_attr_string(ref, names[i]);
        if (!v)
            die_usage("--compare: %s has no %s attribute: the reference must be an nbt-scatter output for the same "
                      "input and medium", o->compare, names[i]);
        if (strcmp(v, want[i]) && !strcmp(names[i], "nbt.phase")) /* an approximate phase against the true one */
            fprintf(stderr, "nbt-scatter: note: --compare: %s was made with %s = %s, this run has %s\n", o->compare,
                    names[i], v, want[i]);
        else if (strcmp(v, want[i]))
            die_usage("--compare: %s was made with %s = %s, this run has %s: the reference must be for the same input "
                      "and medium", o->compare, names[i], v, want[i]);
    }
}

/* The mass of one atom (scale s px) centred at (xc, yc) that falls inside [0, w] x [0, h]: a Gaussian's
 * is a product of erf differences; an erfc atom is the mean of Gaussians of deviation in [0, s]. */
static double gauss_rect(double s, double xc, double yc, double w, double h)
{
    double k = 1.0 / (s * M_SQRT2);
    return 0.25 * (erf((w - xc) * k) + erf(xc * k)) * (erf((h - yc) * k) + erf(yc * k));
}

static double atom_rect(nbt_atom_shape shape, double s, double xc, double yc, double w, double h)
{
    if (shape == NBT_ATOM_GAUSS)
        return gauss_rect(s, xc, yc, w, h);
    /* 16-point Gauss-Legendre on [0, s] (the integrand is smooth: erf of x/s' for s' > 0) */
    static const double X[8] = {0.0950125098376374, 0.2816035507792589, 0.4580167776572274, 0.6178762444026438,
                                0.7554044083550030, 0.8656312023878318, 0.9445750230732326, 0.9894009349916499};
    static const double W[8] = {0.1894506104550685, 0.1826034150449236, 0.1691565193950025, 0.1495959888165767,
                                0.1246289712555339, 0.0951585116824928, 0.0622535239386479, 0.0271524594117541};
    double t = 0;
    for (int i = 0; i < 8; i++)
        t += W[i] * (gauss_rect(0.5 * s * (1 + X[i]), xc, yc, w, h) + gauss_rect(0.5 * s * (1 - X[i]), xc, yc, w, h));
    return 0.5 * t;
}

/* The fraction of pixel (x, y)'s kernel (largest over channels) outside the data window grown by
 * `grow` pixels on each side. */
static double offscreen_px(const nbt_screen_kernel *k, const nbt_image *im, const float *D, double dtheta, size_t x,
                           size_t y, double grow)
{
    size_t i = y * im->w + x;
    double f = 0, px = D[i] * dtheta, xc = (double)x + 0.5 + grow, yc = (double)y + 0.5 + grow,
           W = (double)im->w + 2 * grow, H = (double)im->h + 2 * grow;
    double edge = fmin(fmin(xc, W - xc), fmin(yc, H - yc));
    for (unsigned c = 0; c < nbt_screen_kernel_channels(k) && D[i] > 0 && isfinite(D[i]); c++) {
        nbt_screen_kern kn;
        if (nbt_screen_kernel_eval_ch(k, c, D[i], &kn) != NBT_OK)
            die("the kernel at pixel (%zu, %zu) could not be evaluated", x, y);
        double M = 0, out = 0;
        for (size_t a = 0; a < kn.n; a++)
            M += kn.mass[a];
        for (size_t a = 0; a < kn.n; a++) {
            double s = kn.scale[a] / px;
            if (kn.mass[a] > 1e-6 * M && edge < 9 * s) /* else inside to 1e-19 */
                out += kn.mass[a] * (1.0 - atom_rect(kn.shape[a], s, xc, yc, W, H));
        }
        if (M > 0)
            f = fmax(f, out / M);
    }
    return f;
}

/* Per frame pixel: the fraction of its kernel outside the data window (out, over the data window, 0
 * outside the frame). Returns the frame's mean; *worst the largest. */
static double offscreen(const nbt_screen_kernel *k, const nbt_image *im, const float *D, double dtheta,
                        const frame *fr, float *out, double *worst)
{
    double sum = 0;
    *worst = 0;
    for (size_t i = 0; i < im->w * im->h; i++)
        out[i] = 0;
    for (size_t y = fr->y0; y < fr->y0 + fr->h; y++)
        for (size_t x = fr->x0; x < fr->x0 + fr->w; x++) {
            double f = offscreen_px(k, im, D, dtheta, x, y, 0);
            out[y * im->w + x] = (float)f;
            sum += f;
            *worst = fmax(*worst, f);
        }
    return sum / (double)(fr->w * fr->h);
}

/* the same mean with the data window grown by `grow` pixels per side, from every 4th pixel */
static double offscreen_if(const nbt_screen_kernel *k, const nbt_image *im, const float *D, double dtheta,
                           const frame *fr, double grow)
{
    double sum = 0;
    size_t n = 0;
    for (size_t y = fr->y0 + 1; y < fr->y0 + fr->h; y += 4)
        for (size_t x = fr->x0 + 1; x < fr->x0 + fr->w; x += 4, n++)
            sum += offscreen_px(k, im, D, dtheta, x, y, grow);
    return n ? sum / (double)n : 0;
}

/* the frame's part of a data-window array of n values per pixel */
static double *crop(const double *a, size_t n, const nbt_image *im, const frame *fr)
{
    double *c = malloc(fr->w * fr->h * n * sizeof *c);
    if (!c)
        die("out of memory");
    for (size_t y = 0; y < fr->h; y++)
        memcpy(c + y * fr->w * n, a + ((fr->y0 + y) * im->w + fr->x0) * n, fr->w * n * sizeof *c);
    return c;
}

static void compare(const nbt_image *im, const frame *fr, const float *D, double dtheta,
                    const nbt_screen_kernel *k, const double *S, const double *T3, const nbt_image *ref)
{
    size_t nf = fr->w * fr->h;
    double *Sf = crop(S, 3, im, fr), *Sr = malloc(nf * 3 * sizeof *Sr);
    float *rgb = malloc(nf * 3 * sizeof *rgb), *Df = malloc(nf * sizeof *Df);
    if (!Sr || !rgb || !Df)
        die("out of memory");
    /* the reference's scattered part: its S layer when it has one, else its whole image less T c */
    const nbt_image_channel *rs[3] = {NULL, NULL, NULL}, *re[3] = {NULL, NULL, NULL};
    for (size_t j = 0; j < ref->nchannels; j++)
        for (int c = 0; c < 3; c++) {
            const char *n = ref->channels[j].name, *want = (const char *[]){"S.R", "S.G", "S.B"}[c],
                       *wse = (const char *[]){"Sse.R", "Sse.G", "Sse.B"}[c];
            size_t ln = strlen(n);
            if (ref->channels[j].type != NBT_PIXEL_FLOAT || !ref->channels[j].data)
                continue;
            for (int q = 0; q < 2; q++) {
                const char *wn = q ? wse : want;
                size_t lw = strlen(wn);
                if (ln >= lw && !strcmp(n + ln - lw, wn) && (ln == lw || n[ln - lw - 1] == '.'))
                    (q ? re : rs)[c] = &ref->channels[j];
            }
        }
    for (size_t y = 0; y < fr->h; y++)
        for (size_t x = 0; x < fr->w; x++) {
            size_t i = y * fr->w + x, j = (fr->y0 + y) * im->w + fr->x0 + x;
            Df[i] = D[j];
            for (int c = 0; c < 3; c++) {
                rgb[3 * i + c] = im->rgb[3 * j + c];
                Sr[3 * i + c] = rs[0] && rs[1] && rs[2] ? (double)((const float *)rs[c]->data)[i]
                                                        : (double)ref->rgb[3 * i + c] - T3[3 * j + c] * im->rgb[3 * j + c];
            }
        }
    nbt_screen_input in = {fr->w, fr->h, rgb, Df, dtheta, NULL};
    nbt_screen_metrics mt;
    if (nbt_screen_compare(&in, k, Sf, Sr, &mt) != NBT_OK)
        die("comparison failed");
    double b4 = nbt_screen_binned_rel_l1(fr->w, fr->h, Sf, Sr, 4);
    /* lamp halos: 4x4 bins within 12 px of a lamp (a pixel 10x brighter than the frame's mean) */
    double mean = 0, hd = 0, hr = 0;
    for (size_t i = 0; i < nf * 3; i++)
        mean += rgb[i] / (double)(nf * 3);
    size_t bw = (fr->w + 3) / 4, bh = (fr->h + 3) / 4;
    unsigned char *near = calloc(bw * bh, 1);
    if (!near)
        die("out of memory");
    for (size_t y = 0; y < fr->h; y++)
        for (size_t x = 0; x < fr->w; x++)
            if (rgb[3 * (y * fr->w + x)] + rgb[3 * (y * fr->w + x) + 1] + rgb[3 * (y * fr->w + x) + 2] > 30 * mean)
                for (size_t by = (y > 12 ? y - 12 : 0) / 4; by <= (y + 12) / 4 && by < bh; by++)
                    for (size_t bx = (x > 12 ? x - 12 : 0) / 4; bx <= (x + 12) / 4 && bx < bw; bx++)
                        near[by * bw + bx] = 1;
    for (size_t by = 0; by < bh; by++)
        for (size_t bx = 0; bx < bw; bx++)
            for (int c = 0; c < 3 && near[by * bw + bx]; c++) {
                double a = 0, b = 0;
                for (size_t y = 4 * by; y < 4 * by + 4 && y < fr->h; y++)
                    for (size_t x = 4 * bx; x < 4 * bx + 4 && x < fr->w; x++)
                        a += Sf[3 * (y * fr->w + x) + (size_t)c], b += Sr[3 * (y * fr->w + x) + (size_t)c];
                hd += fabs(a - b);
                hr += fabs(b);
            }
    printf("relL1 %.6g relRMS %.6g edge %.6g bias %.6g max %.6g binned4 %.6g halo %.6g", mt.rel_l1, mt.rel_rms,
           mt.edge, mt.bias, mt.max, b4, hr > 0 ? hd / hr : 0.0);
    if (re[0] && re[1] && re[2]) { /* a path-traced reference: its own noise in the same measure */
        double *se = malloc(nf * 3 * sizeof *se);
        if (!se)
            die("out of memory");
        for (size_t i = 0; i < nf * 3; i++)
            se[i] = ((const float *)re[i % 3]->data)[i / 3];
        printf(" ref_noise4 %.6g", nbt_screen_binned_noise(fr->w, fr->h, Sr, se, 4));
        free(se);
    }
    printf("\n");
    free(near);
    free(Sf);
    free(Sr);
    free(rgb);
    free(Df);
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
    struct stat si, so;
    if (stat(o.in, &si) == 0 && stat(o.out, &so) == 0 && si.st_dev == so.st_dev && si.st_ino == so.st_ino)
        die_usage("-o: '%s' is the input render: write the fogged image to another file", o.out);

    char err[512];
    nbt_image *im = NULL, *ref = NULL;
    nbt_status st = nbt_image_read_exr(o.in, &im, err, sizeof err);
    if (st != NBT_OK)
        die_usage("%s", err);
    if (!im->z)
        die_usage("%s: no depth channel Z: nbt-scatter needs R, G, B and Z (Blender: enable the Z pass)", o.in);
    if (o.disp_given)
        im->display = o.disp;
    frame fr = frame_of(&o, im);
    int overscan = fr.w != im->w || fr.h != im->h;
    if (overscan && o.density)
        die_usage("--density with an overscanned render (data window larger than the display window): not "
                  "supported; crop the render to its display window");
    if (o.compare) {
        if (nbt_image_read_exr(o.compare, &ref, err, sizeof err) != NBT_OK)
            die_usage("--compare: %s", err);
        if (ref->w != fr.w || ref->h != fr.h)
            die_usage("--compare: %s is %zux%zu, the input's frame %zux%zu", o.compare, ref->w, ref->h, fr.w, fr.h);
    }
    if (o.model_path) {
        if (nbt_screen_model_read(o.model_path, &o.med.owned_model, err, sizeof err) != NBT_OK)
            die_usage("--model: %s", err);
        o.med.model = o.med.owned_model;
    }
    nbt_kernel_correction corr;
    if (o.corr_path && nbt_kernel_correction_read(o.corr_path, &corr, err, sizeof err) != NBT_OK)
        die_usage("--correction: %s", err);
    nbt_grid *grid = o.density ? load_grid(&o) : NULL;

    nbt_set_error_handler(on_error); /* file errors above come back in err */
    double dtheta = 2.0 * tan(o.fov * M_PI / 360.0) / (double)fr.h;
    float *D = ray_distances(&o, im, &fr, dtheta);
    medium_attrs ma;
    medium_attrs_fill(&o, input_hash(im, &fr), &ma);
    if (ref)
        check_reference(&o, ref, &ma);
    nbt_screen_kernel *k = medium_kernel(&o.med, (nbt_skernel_kind)o.kernel, o.corr_path ? &corr : NULL);
    size_t np = im->w * im->h;
    double *S = calloc(np * 3, sizeof *S), *T = malloc(np * sizeof *T), *T3 = malloc(np * 3 * sizeof *T3),
           *Sse = NULL;
    if (!S || !T || !T3)
        die("out of memory");
    for (size_t i = 0; i < np * 3; i++) /* the direct part, per channel */
        T3[i] = D[i / 3] == 0 ? 1.0 : isfinite(D[i / 3]) ? exp(-o.med.sigma_t[i % 3] * D[i / 3]) : 0.0;
    nbt_screen_input in = {im->w, im->h, im->rgb, D, dtheta, NULL};
    nbt_screen_rule rule = o.method == 1 ? NBT_SCREEN_SOURCE : NBT_SCREEN_NEAR;
    double t0 = now();
    const char *how = "layered FFT";
    nbt_beam_medium bm = nbt_beam_homogeneous(o.med.sigma_t[0], o.med.albedo[0], o.med.B);
    nbt_screen_pixkern *pix = grid ? medium_kernels(&o, grid, &in, &bm) : NULL;
    in.pix = pix;
    char qhow[160];
    double gpu_ms = -1;
    unsigned long spp_done = 0;
    /* beyond the data window the CPU operators see the border continued as its mirror image (colour and planar
     * depth): a wall that runs out of the frame keeps sending light, and a lamp cut by the edge is seen once
     * more, not smeared into a streak as repeating the edge pixels would */
    size_t P = o.method <= 1 && !pix ? (size_t)lround(o.extend * (double)(fr.w > fr.h ? fr.w : fr.h)) : 0;
    float *xrgb = NULL, *xD = NULL;
    double *xS = NULL, *Sop = S;
    if (P) {
        size_t W = im->w + 2 * P, H = im->h + 2 * P;
        xrgb = malloc(W * H * 3 * sizeof *xrgb), xD = malloc(W * H * sizeof *xD), xS = malloc(W * H * 3 * sizeof *xS);
        float *band = malloc(im->w * im->h * sizeof *band);
        if (!xrgb || !xD || !xS || !band)
            die("out of memory");
        /* lamps are not continued: the mirror's brightness is capped at 4x the median of the border band */
        size_t nb = 0;
        for (size_t y = 0; y < im->h; y++)
            for (size_t x = 0; x < im->w; x++)
                if (x < 8 || y < 8 || x + 8 >= im->w || y + 8 >= im->h)
                    band[nb++] = im->rgb[3 * (y * im->w + x)] + im->rgb[3 * (y * im->w + x) + 1] +
                                 im->rgb[3 * (y * im->w + x) + 2];
        qsort(band, nb, sizeof *band, cmp_float);
        double cap = 4.0 * band[nb / 2];
        free(band);
        for (size_t y = 0; y < H; y++)
            for (size_t x = 0; x < W; x++) {
                long sx = (long)x - (long)P, sy = (long)y - (long)P;
                size_t cx = mirror(sx, im->w), cy = mirror(sy, im->h);
                size_t j = cy * im->w + cx, i = y * W + x;
                int beyond = sx < 0 || sy < 0 || sx >= (long)im->w || sy >= (long)im->h;
                memcpy(xrgb + 3 * i, im->rgb + 3 * j, 3 * sizeof *xrgb);
                double lum = (double)xrgb[3 * i] + xrgb[3 * i + 1] + xrgb[3 * i + 2];
                if (beyond && lum > cap)
                    for (int c = 0; c < 3; c++)
                        xrgb[3 * i + c] = (float)(xrgb[3 * i + c] * cap / lum);
                xD[i] = !beyond || !isfinite(D[j]) || o.ray_depth || D[j] == 0
                            ? D[j] : (float)(im->z[j] * ray_factor(&fr, dtheta, sx, sy));
            }
        in = (nbt_screen_input){W, H, xrgb, xD, dtheta, NULL};
        Sop = xS;
    }
    if (o.method == 3) {
        const nbt_phase *ph = medium_phase(&o.med, 0);
        nbt_phase *gph = NULL;
        if (!o.med.nphase && !(ph = gph = nbt_phase_gauss(o.med.B)))
            die("out of memory");
        for (int c = 1; c < 3; c++)
            if (strcmp(nbt_phase_name(medium_phase(&o.med, c) ? medium_phase(&o.med, c) : ph), nbt_phase_name(ph)))
                die_usage("--method path: one phase for all channels (the path tracer samples one phase)");
        nbt_screen_world wd = {im->w, im->h, im->rgb, im->z, dtheta, fr.cx, fr.cy, fr.x0, fr.y0, fr.w, fr.h};
        nbt_screen_path_medium pm;
        memset(&pm, 0, sizeof pm);
        for (int c = 0; c < 3; c++)
            pm.sigma_t[c] = o.med.sigma_t[c], pm.albedo[c] = o.med.albedo[c];
        pm.phase = ph;
        pm.radius = INFINITY;
        nbt_screen_path_opts po;
        memset(&po, 0, sizeof po);
        po.spp = (unsigned long)o.spp;
        po.target_noise = o.noise;
        po.max_spp = 1ul << 24;
        po.bin = 4;
        po.seed = o.seed;
        po.nthreads = (unsigned)o.threads;
        po.progress = 1;
        size_t nf = fr.w * fr.h;
        double *Sp = malloc(nf * 3 * sizeof *Sp), *sp = malloc(nf * 3 * sizeof *sp);
        Sse = calloc(np * 3, sizeof *Sse);
        if (!Sp || !sp || !Sse)
            die("out of memory");
        if ((st = nbt_screen_path(&wd, &pm, &po, Sp, sp, &spp_done)) != NBT_OK)
            die("--method path failed: %s", nbt_strerror(st));
        double noise = nbt_screen_binned_noise(fr.w, fr.h, Sp, sp, 4);
        for (size_t y = 0; y < fr.h; y++)
            for (size_t x = 0; x < fr.w; x++)
                for (int c = 0; c < 3; c++) {
                    size_t i = ((fr.y0 + y) * im->w + fr.x0 + x) * 3 + (size_t)c;
                    S[i] = Sp[(y * fr.w + x) * 3 + (size_t)c];
                    Sse[i] = sp[(y * fr.w + x) * 3 + (size_t)c];
                }
        snprintf(qhow, sizeof qhow, "path tracing (%lu samples per pixel, 4x4-binned noise %.3g%%)", spp_done,
                 100 * noise);
        how = qhow;
        free(Sp);
        free(sp);
        nbt_phase_free(gph);
    } else if (o.method == 2) {
#ifdef HAVE_GL
        run_gl(&o, &in, k, S, T, &gpu_ms);
        snprintf(qhow, sizeof qhow, "GL (%.3f ms GPU time)", gpu_ms);
        how = qhow;
#endif
    } else if (o.quantize > 0) {
        const float *Din = in.D;
        float *Dq = malloc(in.w * in.h * sizeof *Dq);
        if (!Dq)
            die("out of memory");
        nbt_screen_quantize(Din, in.w * in.h, (size_t)o.quantize, Dq);
        in.D = Dq;
        st = nbt_screen_layered(&in, k, rule, o.tail, (size_t)o.quantize + 2 /* sky, D = 0 */, (unsigned)o.threads,
                                Sop, NULL);
        in.D = Din;
        free(Dq);
        snprintf(qhow, sizeof qhow, "layered FFT on %ld quantised layers (approximate)", o.quantize);
        how = qhow;
    } else {
        /* the FFT is exact when the distances form few layers; it says EDOM otherwise */
        nbt_set_error_handler(NULL);
        st = o.layers > 0 && !pix
                 ? nbt_screen_layered(&in, k, rule, o.tail, (size_t)o.layers, (unsigned)o.threads, Sop, P ? NULL : T)
                 : NBT_EDOM;
        nbt_set_error_handler(on_error);
        if (st == NBT_EDOM && o.quantize < 0 && o.med.nphase && !pix) {
            /* continuous depth and a wide kernel: brute force would take minutes; 64 layers cost ~0.3% */
            const float *Din = in.D;
            float *Dq = malloc(in.w * in.h * sizeof *Dq);
            if (!Dq)
                die("out of memory");
            nbt_screen_quantize(Din, in.w * in.h, 64, Dq);
            in.D = Dq;
            st = nbt_screen_layered(&in, k, rule, o.tail, 66, (unsigned)o.threads, Sop, NULL);
            in.D = Din;
            free(Dq);
            how = "layered FFT on 64 quantised layers (the depth has more than --layers values; --quantize 0: exact)";
        } else if (st == NBT_EDOM) {
            how = "brute force";
            if (in.w * in.h > 40000 && !pix)
                fprintf(stderr, "nbt-scatter: more than %ld depth layers: brute force over %zu pixels, which can take "
                                "minutes; --quantize 64 is an approximate, fast alternative (measure it with "
                                "--compare)\n", o.layers, in.w * in.h);
            st = nbt_screen_brute(&in, k, rule, o.tail, (unsigned)o.threads, Sop, P ? NULL : T);
        }
    }
    if (st != NBT_OK)
        die("scattering failed: %s", nbt_strerror(st));
    if (P) { /* back to the data window */
        for (size_t y = 0; y < im->h; y++)
            memcpy(S + y * im->w * 3, xS + ((y + P) * in.w + P) * 3, im->w * 3 * sizeof *S);
        in = (nbt_screen_input){im->w, im->h, im->rgb, D, dtheta, NULL};
        free(xrgb);
        free(xD);
        free(xS);
    }
    if (pix || o.method == 2)
        for (size_t i = 0; i < np * 3; i++) /* per-pixel kernels and the GL methods give their own T */
            T3[i] = T[i / 3];
    double t1 = now();
    fprintf(stderr, "nbt-scatter: %s (%s, %s kernel) by %s, %zux%zu%s: %.3f s\n", o.method_name, method_goal(&o),
            o.method == 3 ? "no" : kernel_label(&o), how, im->w, im->h, overscan ? " (overscan)" : "", t1 - t0);

    /* light from outside the data window: how much of the frame's kernels falls there */
    float *off = malloc(np * sizeof *off);
    if (!off)
        die("out of memory");
    double worst = 0, mean = o.method == 3 || pix ? 0 : offscreen(k, im, D, dtheta, &fr, off, &worst);
    if (o.method == 3 || pix)
        memset(off, 0, np * sizeof *off);
    if (worst > 0.01) {
        /* what more overscan would recover: the frame's mean with the data window grown */
        double g15 = offscreen_if(k, im, D, dtheta, &fr, 0.15 * (double)fr.w),
               g50 = offscreen_if(k, im, D, dtheta, &fr, 0.5 * (double)fr.w);
        fprintf(stderr, "nbt-scatter: warning: the kernels reach beyond the %s: on average %.1f%% of a frame "
                        "pixel's kernel (at most %.1f%%) falls outside it, and that light is missing; 15%% more "
                        "overscan per side would leave %.1f%%, 50%% would leave %.1f%% (layer offscreen.X has "
                        "the fraction per pixel; doc/screenspace.md)\n",
                overscan ? "overscanned render" : "image (render with overscan)", 100 * mean, 100 * worst,
                100 * g15, 100 * g50);
    }
    if (ref)
        compare(im, &fr, D, dtheta, k, S, T3, ref);

    /* the frame: direct plus scattered, with S, T and the off-screen fraction as layers */
    nbt_image *out = nbt_image_alloc(im->w, im->h, 1);
    float *Sf = malloc(np * 3 * sizeof *Sf), *Tf = malloc(np * 3 * sizeof *Tf), *Ef = NULL;
    if (!out || !Sf || !Tf || nbt_image_copy_meta(out, im) != NBT_OK)
        die("out of memory");
    for (size_t i = 0; i < np * 3; i++) {
        out->rgb[i] = (float)(T3[i] * im->rgb[i] + S[i]);
        Sf[i] = (float)S[i];
        Tf[i] = (float)T3[i];
    }
    memcpy(out->z, im->z, np * sizeof *out->z);
    static const char *const RGB[] = {"R", "G", "B"}, *const X[] = {"X"};
    nbt_image_layer layers[4] = {{"S", 3, RGB, Sf}, {"T", 3, RGB, Tf}, {"offscreen", 1, X, off}, {"Sse", 3, RGB, NULL}};
    size_t nlayers = 3;
    if (Sse) {
        if (!(Ef = malloc(np * 3 * sizeof *Ef)))
            die("out of memory");
        for (size_t i = 0; i < np * 3; i++)
            Ef[i] = (float)Sse[i];
        layers[3].data = Ef;
        nlayers = 4;
    }
    char sb[32], sspp[32], sseed[32];
    snprintf(sb, sizeof sb, "%.17g", o.med.B);
    snprintf(sspp, sizeof sspp, "%lu", spp_done);
    snprintf(sseed, sizeof sseed, "%llu", o.seed);
    const char *attrs[32];
    size_t na = 0;
#define ATTR(n, v) (attrs[na++] = (n), attrs[na++] = (v))
    ATTR("nbt.method", o.method_name);
    ATTR("nbt.kernel", o.method == 3 ? "none" : kernel_label(&o));
    ATTR("nbt.sigma_t", ma.st);
    ATTR("nbt.albedo", ma.alb);
    ATTR("nbt.phase", ma.phases);
    ATTR("nbt.fov_y", ma.fov);
    ATTR("nbt.depth", o.ray_depth ? "ray" : "plane");
    ATTR("nbt.geometry", o.med.geometry == NBT_SCREEN_ENTERING ? "entering" : "inside");
    ATTR("nbt.input", ma.hash);
    ATTR("nbt.version", nbt_version());
    if (!o.med.nphase)
        ATTR("nbt.B", sb);
    if (o.method == 3) {
        ATTR("nbt.seed", sseed);
        ATTR("nbt.spp", sspp);
    }
#undef ATTR
    nbt_exr_write_opts wo;
    memset(&wo, 0, sizeof wo);
    wo.window = &im->display;
    wo.layers = layers;
    wo.nlayers = nlayers;
    wo.attrs = attrs;
    wo.nattrs = na / 2;
    /* preview first (of the frame), so that a failed EXR write can take it back: all or nothing */
    char *png = o.png ? png_path(o.out) : NULL;
    if (png) {
        nbt_image *pv = nbt_image_alloc(fr.w, fr.h, 0);
        if (!pv)
            die("out of memory");
        for (size_t y = 0; y < fr.h; y++)
            memcpy(pv->rgb + y * fr.w * 3, out->rgb + ((fr.y0 + y) * im->w + fr.x0) * 3, fr.w * 3 * sizeof(float));
        if (scatter_preview_png(pv, png) != 0)
            die("cannot write the preview '%s'", png);
        nbt_image_free(pv);
    }
    if (nbt_image_write_exr_ex(out, o.out, &wo, err, sizeof err) != NBT_OK) {
        if (png)
            unlink(png);
        die("%s", err);
    }
    free(png);
    nbt_image_free(out);
    nbt_image_free(im);
    nbt_image_free(ref);
    nbt_screen_kernel_free(k);
    medium_free(&o.med);
    nbt_grid_free(grid);
    free(pix);
    free(D);
    free(S);
    free(T);
    free(T3);
    free(Sse);
    free(Sf);
    free(Tf);
    free(Ef);
    free(off);
    return 0;
}
