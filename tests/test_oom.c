/* tests/test_oom.c: allocation-failure injection for libnbt.
 *
 * This executable defines malloc, calloc, realloc, free and the aligned
 * allocators itself, forwarding to glibc's __libc_* functions; ELF symbol
 * interposition makes libnbt.so (and OpenEXR, libstdc++, libc's own strdup
 * ...) call them. Once armed with k, the k-th allocation from that point
 * returns NULL (just that one). For each call under test and k = 1, 2, ...
 * until the call makes fewer than k allocations (so none failed), it checks:
 *   - an injected failure gives the documented status (NBT_ENOMEM, or NULL
 *     for the allocating constructors), never a crash;
 *   - the reason says "memory" (in err for a call that takes err and
 *     errlen, else through the error handler);
 *   - nothing leaks: the live allocation count after the call (and after
 *     freeing what the caller owns) equals the count before it;
 *   - a call that succeeds (with no failure injected, or one the code
 *     recovered from) gives bit for bit the result of a reference call
 *     made without injection, so a mutant in the success path shows too.
 * Every call runs with one thread: the k-th allocation is then the same one
 * on every run. FFTW's own allocations are exempt (its planner aborts on a
 * failed one). OOM_TRACE=1 prints a backtrace at each injected failure.
 *
 * ASan (configure --enable-sanitizers) replaces malloc itself, so the
 * injector cannot work there: the test then exits 77 (SKIP). */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* dl_iterate_phdr */
#endif
#include <config.h>
#include <dirent.h>
#include <link.h>
#include <errno.h>
#include <execinfo.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <nbt/nbt.h>
#include <nbt/image.h>
#include <nbt/gslice.h>

#if defined(__SANITIZE_ADDRESS__)
#define OOM_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define OOM_SANITIZED 1
#endif
#endif

#ifdef OOM_SANITIZED
int main(void)
{
    printf("SKIP: built with AddressSanitizer, which owns malloc; the allocation-failure injector cannot interpose\n");
    return 77;
}
#else
#include "testutil.h"

/* ---- the injector ---- */
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);
extern void *__libc_memalign(size_t, size_t);
void *memalign(size_t, size_t);
void *valloc(size_t);

static atomic_long live;      /* allocations not yet freed */
static atomic_long countdown; /* armed: the allocation that takes it from 1 to 0 fails */
static atomic_int armed, injected;
static int trace;

/* FFTW's planner aborts the process when an allocation fails (its alloc.c asserts, by design), which
 * no caller can handle: allocations made from inside libfftw3 are never failed (nor counted towards k).
 * Its text segment, found before any arming. */
static uintptr_t fftw_lo, fftw_hi;
static int find_fftw(struct dl_phdr_info *info, size_t size, void *data)
{
    (void)size, (void)data;
    if (!strstr(info->dlpi_name, "libfftw3"))
        return 0;
    for (int i = 0; i < info->dlpi_phnum; i++)
        if (info->dlpi_phdr[i].p_type == PT_LOAD && (info->dlpi_phdr[i].p_flags & PF_X)) {
            fftw_lo = info->dlpi_addr + info->dlpi_phdr[i].p_vaddr;
            fftw_hi = fftw_lo + info->dlpi_phdr[i].p_memsz;
        }
    return 1;
}

static int inject_from(const void *caller)
{
    if (!atomic_load(&armed) || ((uintptr_t)caller >= fftw_lo && (uintptr_t)caller < fftw_hi))
        return 0;
    if (atomic_fetch_sub(&countdown, 1) == 1) {
        atomic_fetch_add(&injected, 1);
        errno = ENOMEM; /* as glibc's malloc does: fopen and friends report it */
        if (trace) { /* OOM_TRACE=1: where each injected failure happens (debugging aid) */
            void *bt[24];
            backtrace_symbols_fd(bt, backtrace(bt, 24), 1);
            write(1, "--\n", 3);
        }
        return 1;
    }
    return 0;
}

static void *counted(void *p)
{
    if (p)
        atomic_fetch_add(&live, 1);
    return p;
}

#define inject() inject_from(__builtin_return_address(0))

void *malloc(size_t n)
{
    return inject() ? NULL : counted(__libc_malloc(n));
}

void *calloc(size_t a, size_t b)
{
    return inject() ? NULL : counted(__libc_calloc(a, b));
}

void *realloc(void *p, size_t n)
{
    if (!p)
        return inject() ? NULL : counted(__libc_malloc(n));
    if (n == 0) { /* glibc: frees p, returns NULL */
        free(p);
        return NULL;
    }
    if (inject())
        return NULL; /* p stays allocated, as a real failure leaves it */
    return __libc_realloc(p, n);
}

void free(void *p)
{
    if (p)
        atomic_fetch_sub(&live, 1);
    __libc_free(p);
}

void *memalign(size_t al, size_t n)
{
    return inject() ? NULL : counted(__libc_memalign(al, n));
}

void *aligned_alloc(size_t al, size_t n)
{
    return inject() ? NULL : counted(__libc_memalign(al, n));
}

int posix_memalign(void **out, size_t al, size_t n)
{
    void *p = inject() ? NULL : counted(__libc_memalign(al, n));
    if (!p)
        return ENOMEM;
    *out = p;
    return 0;
}

void *valloc(size_t n)
{
    return inject() ? NULL : counted(__libc_memalign((size_t)sysconf(_SC_PAGESIZE), n));
}

static void arm(long k)
{
    atomic_store(&injected, 0);
    atomic_store(&countdown, k);
    atomic_store(&armed, 1);
}

/* returns how many allocations were made to fail (0 or 1) */
static int disarm(void)
{
    atomic_store(&armed, 0);
    return atomic_load(&injected);
}

/* ---- the runner ---- */
static char reason[512]; /* the error handler's last reason */
static void on_error(const char *r, nbt_status s)
{
    (void)s;
    snprintf(reason, sizeof reason, "%s", r);
}

enum { RES_MAX = 1 << 16, K_MAX = 20000 };
static double res[RES_MAX], ref[RES_MAX];

typedef struct {
    const char *name;
    int msg; /* an injected failure must come with a reason saying "memory": 1 through the error handler or
                err, 2 in err (an API with err and errlen) */
    void (*setup)(void);                /* unarmed: inputs the call needs (may be NULL) */
    nbt_status (*call)(char *err, size_t errlen); /* the call under test; NBT_ENOMEM for a NULL constructor result */
    size_t (*finish)(int ok, double *out); /* unarmed: copy the result (ok) to out, return its length; free
                                              what the caller owns */
    int warm; /* run once before counting: a library that caches on first use (FFTW's planner keeps its
                 twiddle tables and wisdom until fftw_cleanup) */
} oom_case;

static int says_memory(const char *s)
{
    return strstr(s, "memory") != NULL;
}

static void run_case(const oom_case *c)
{
    clock_t c0 = clock();
    char err[512] = "";
    long live0 = atomic_load(&live);
    reason[0] = '\0';
    if (c->warm) {
        if (c->setup)
            c->setup();
        c->finish(c->call(err, sizeof err) == NBT_OK, ref);
        live0 = atomic_load(&live);
    }
    if (c->setup)
        c->setup();
    nbt_status st = c->call(err, sizeof err);
    size_t nref = c->finish(st == NBT_OK, ref);
    if (st != NBT_OK || atomic_load(&live) != live0) {
        t_true(0, "%s: reference call (status %d, %ld allocations left): %s %s", c->name, st,
               atomic_load(&live) - live0, err, reason);
        return;
    }
    long k, nfail = 0, nrecover = 0, bad_status = 0, bad_msg = 0, leaks = 0, differs = 0;
    for (k = 1; k <= K_MAX; k++) {
        live0 = atomic_load(&live);
        if (c->setup)
            c->setup();
        err[0] = reason[0] = '\0';
        arm(k);
        st = c->call(err, sizeof err);
        int inj = disarm();
        size_t n = c->finish(st == NBT_OK, res);
        long left = atomic_load(&live) - live0;
        if (left != 0 && leaks++ < 3)
            printf("      %s: k = %ld (status %d): %ld allocations leaked\n", c->name, k, st, left);
        if (st == NBT_OK) {
            if (n != nref || memcmp(res, ref, n * sizeof *res) != 0) {
                if (getenv("OOM_DEBUG"))
                    for (size_t i = 0; i < n && i < nref; i++)
                        if (memcmp(&res[i], &ref[i], sizeof *res))
                            printf("        [%zu] %.17g vs %.17g\n", i, res[i], ref[i]);
                if (differs++ < 3)
                    printf("      %s: k = %ld: result differs from the reference (%zu vs %zu values)\n", c->name,
                           k, n, nref);
            }
            if (!inj)
                break;
            nrecover++;
        } else {
            nfail++;
            if (!inj || st != NBT_ENOMEM) {
                if (bad_status++ < 3)
                    printf("      %s: k = %ld: status %d (%s) with %d failures injected, want NBT_ENOMEM (%s%s)\n",
                           c->name, k, st, nbt_strerror(st), inj, err, reason);
            } else if (c->msg && !says_memory(err) && (c->msg == 2 || !says_memory(reason))) {
                if (bad_msg++ < 3)
                    printf("      %s: k = %ld: reason \"%s\" / \"%s\" does not say memory\n", c->name, k, err,
                           reason);
            }
        }
    }
    t_true(k <= K_MAX && !bad_status && !bad_msg && !leaks && !differs,
           "%s: %ld allocations, %ld failures caught, %ld recovered, result bitwise equal (%.2f s)", c->name, k - 1,
           nfail, nrecover, (double)(clock() - c0) / CLOCKS_PER_SEC);
}

/* ---- the cases ---- */
static size_t put_table(const nbt_table *t, double *out)
{
    size_t n = 0;
    out[n++] = (double)t->nch;
    for (int a = 0; a < 3; a++)
        out[n++] = (double)t->axis[a].n, out[n++] = t->axis[a].lo, out[n++] = t->axis[a].hi;
    for (size_t c = 0; c < t->nch; c++)
        out[n++] = t->max_err[c], out[n++] = t->max_abs[c], out[n++] = t->k[c];
    out[n++] = t->quad_err;
    size_t nv = nbt_table_size(t);
    for (size_t i = 0; i < nv && n < RES_MAX; i++)
        out[n++] = t->data[i];
    if (t->cell_err)
        for (size_t i = 0; i < (t->axis[2].n - 1) * t->nch; i++)
            out[n++] = t->cell_err[i];
    if (t->row_err)
        for (size_t i = 0; i < nbt_table_row_err_len(t); i++)
            out[n++] = t->row_err[i];
    if (t->theta_err)
        for (size_t i = 0; i < nbt_table_theta_err_len(t); i++)
            out[n++] = t->theta_err[i];
    return n;
}

/* nbt_table_alloc3 + nbt_table_dup */
static nbt_table *tab;
static nbt_status call_table_dup(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    nbt_axis a0 = {0, 2, NBT_AXIS_LINEAR, 0, 5}, a1 = {-1, 1, NBT_AXIS_COS, 0, 3}, a2 = {-0.5, 0.5, NBT_AXIS_ATANH, 0, 4};
    nbt_table *t = nbt_table_alloc3(NBT_TABLE_H, &a0, &a1, &a2, 3);
    if (!t)
        return NBT_ENOMEM;
    for (size_t i = 0; i < nbt_table_size(t); i++)
        t->data[i] = (float)(i * 0.25 - 3.0);
    for (size_t i = 0; i < 3 * 3; i++)
        t->cell_err[i] = 1e-3 * (double)(i + 1);
    if (nbt_table_row_err_alloc(t) != NBT_OK || nbt_table_theta_err_alloc(t, 1) != NBT_OK) {
        nbt_table_free(t);
        return NBT_ENOMEM;
    }
    for (size_t i = 0; i < nbt_table_row_err_len(t); i++)
        t->row_err[i] = 2e-3 * (double)(i + 1);
    for (size_t i = 0; i < nbt_table_theta_err_len(t); i++)
        t->theta_err[i] = 5e-4 * (double)(i % 7);
    tab = nbt_table_dup(t);
    nbt_table_free(t);
    return tab ? NBT_OK : NBT_ENOMEM;
}
static size_t fin_table(int ok, double *out)
{
    size_t n = ok ? put_table(tab, out) : 0;
    nbt_table_free(tab);
    tab = NULL;
    return n;
}

/* nbt_h_table_build with the error measurement (orders 0..2, 9 x 5 nodes) */
static void setup_h(void)
{
    nbt_axis a0 = {0, 4, NBT_AXIS_SQRT, 0, 9}, a1 = {-1.5707963267948966, 1.5707963267948966, NBT_AXIS_COS, 0, 5};
    tab = nbt_table_alloc(NBT_TABLE_H, &a0, &a1, 3);
    for (int c = 0; c < 3; c++)
        tab->k[c] = c;
}
static nbt_status call_h(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    nbt_build_opts o = {1e-6, 1, 1};
    return nbt_h_table_build(tab, NULL, &o);
}

/* ---- EXR tables: write (into an empty directory) and read back ---- */
static char dir[64], path_tab[128], path_img[128], path_out[128], path_txt[128], path_beamfit[128], path_corr[128];

/* files in dir besides the inputs the cases keep there: a failed write must leave none */
static int dir_entries(void)
{
    DIR *d = opendir(dir);
    int n = 0;
    if (!d)
        return -1;
    for (struct dirent *e; (e = readdir(d));)
        n += e->d_name[0] != '.';
    closedir(d);
    return n;
}
static int dir_base; /* entries before a write */

static void setup_tab_write(void)
{
    nbt_axis a0 = {0, 3, NBT_AXIS_LOG1P_CBRT, 10, 6}, a1 = {-1.5, 1.5, NBT_AXIS_COS, 0, 4}, a2 = {-0.4, 0.7, NBT_AXIS_ATANH, 0, 3};
    tab = nbt_table_alloc3(NBT_TABLE_J, &a0, &a1, &a2, 2);
    tab->n = 1, tab->k[0] = 0, tab->k[1] = 1, tab->interp2 = 2, tab->quad_tol = 1e-6;
    for (size_t i = 0; i < nbt_table_size(tab); i++)
        tab->data[i] = (float)(0.5 + 0.125 * (double)i);
    for (size_t i = 0; i < 2 * 2; i++)
        tab->cell_err[i] = 1e-4 * (double)(i + 1);
    tab->max_err[0] = 2e-4, tab->max_err[1] = 4e-4, tab->max_abs[0] = 5, tab->max_abs[1] = 9;
    nbt_table_row_err_alloc(tab);
    for (size_t i = 0; i < nbt_table_row_err_len(tab); i++)
        tab->row_err[i] = 1e-5 * (double)(i + 1);
    dir_base = dir_entries();
}
static nbt_status call_tab_write(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    return nbt_table_write_exr(tab, path_out, NBT_EXR_ZIP);
}
static size_t fin_tab_write(int ok, double *out)
{
    size_t n = 0;
    nbt_table_free(tab);
    tab = NULL;
    if (ok) {
        char e[256];
        if (nbt_table_read_exr(path_out, &tab, e, sizeof e) == NBT_OK)
            n = put_table(tab, out);
        nbt_table_free(tab);
        tab = NULL;
        unlink(path_out);
    } else if (dir_entries() != dir_base) {
        printf("      table_write_exr: a failed write left a file behind\n");
        out[n++] = -1; /* never equals the reference, whose first value is nch >= 1 */
        unlink(path_out);
    }
    return n;
}
static nbt_status call_tab_read(char *err, size_t errlen)
{
    return nbt_table_read_exr(path_tab, &tab, err, errlen);
}

/* ---- EXR images ---- */
static nbt_image *img, *img2;
static const char *const lay_ch[] = {"R", "G", "B"}, *const one_ch[] = {"X"};
static float lay_data[7 * 5 * 3], one_data[7 * 5];
static size_t put_image(const nbt_image *im, double *out)
{
    size_t n = 0, np = im->w * im->h;
    out[n++] = (double)im->w, out[n++] = (double)im->h, out[n++] = im->x0, out[n++] = im->y0;
    out[n++] = im->display.min_x, out[n++] = im->display.max_y;
    for (size_t i = 0; i < 3 * np; i++)
        out[n++] = im->rgb[i];
    for (size_t i = 0; im->z && i < np; i++)
        out[n++] = im->z[i];
    for (const char *q = im->rgb_layer; q && *q; q++)
        out[n++] = *q;
    for (const char *q = im->z_name; q && *q; q++)
        out[n++] = *q;
    out[n++] = (double)im->nchannels;
    for (size_t c = 0; c < im->nchannels; c++) {
        for (const char *q = im->channels[c].name; *q; q++)
            out[n++] = *q;
        out[n++] = im->channels[c].type;
        for (size_t i = 0; im->channels[c].data && i < np; i++)
            out[n++] = im->channels[c].type == NBT_PIXEL_FLOAT ? ((const float *)im->channels[c].data)[i]
                       : im->channels[c].type == NBT_PIXEL_HALF ? ((const uint16_t *)im->channels[c].data)[i]
                                                                : ((const uint32_t *)im->channels[c].data)[i];
    }
    size_t na = nbt_image_attr_count(im);
    out[n++] = (double)na;
    for (size_t i = 0; i < na; i++) {
        const char *type = NULL, *name = nbt_image_attr_name(im, i, &type);
        for (const char *q = name; q && *q; q++)
            out[n++] = *q;
        for (const char *q = type; q && *q; q++)
            out[n++] = *q;
        const char *v = nbt_image_attr_string(im, name);
        for (const char *q = v; q && *q; q++)
            out[n++] = *q;
    }
    return n;
}
static nbt_status call_img_read(char *err, size_t errlen)
{
    return nbt_image_read_exr(path_img, &img, err, errlen);
}
static size_t fin_img(int ok, double *out)
{
    size_t n = ok ? put_image(img, out) : 0;
    nbt_image_free(img);
    img = NULL;
    return n;
}
/* the image read from path_img (layers, kept channels and attributes), written cropped with a layer */
static void setup_img_write(void)
{
    char e[256];
    nbt_image_read_exr(path_img, &img2, e, sizeof e);
    dir_base = dir_entries();
}
static nbt_status call_img_write(char *err, size_t errlen)
{
    nbt_box2i win = {img2->x0 + 1, img2->y0 + 2, img2->x0 + 5, img2->y0 + 4};
    static const char *const attrs[] = {"nbt.method", "oom", "owner", "test"};
    nbt_image_layer ly = {"S", 3, lay_ch, lay_data};
    nbt_exr_write_opts o = {.window = &win, .layers = &ly, .nlayers = 1, .attrs = attrs, .nattrs = 2};
    return nbt_image_write_exr_ex(img2, path_out, &o, err, errlen);
}
static size_t fin_img_write(int ok, double *out)
{
    size_t n = 0;
    nbt_image_free(img2);
    img2 = NULL;
    if (ok) {
        char e[256];
        if (nbt_image_read_exr(path_out, &img, e, sizeof e) == NBT_OK)
            n = put_image(img, out);
        nbt_image_free(img);
        img = NULL;
        unlink(path_out);
    } else if (dir_entries() != dir_base) {
        printf("      image_write_exr_ex: a failed write left a file behind\n");
        out[n++] = -1;
        unlink(path_out);
    }
    return n;
}
/* copy_meta: dst keeps its pixels, gets img2's metadata; unchanged on failure */
static void setup_copy_meta(void)
{
    char e[256];
    nbt_image_read_exr(path_img, &img2, e, sizeof e);
    img = nbt_image_alloc(7, 5, 1);
    img->rgb[4] = 2.5f;
}
static nbt_status call_copy_meta(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    return nbt_image_copy_meta(img, img2);
}
static size_t fin_copy_meta(int ok, double *out)
{
    size_t n = put_image(img, out);
    if (!ok) { /* unchanged: nothing of img2's kept, its own origin */
        if (img->nchannels || img->attrs || img->rgb_layer || img->z_name || img->x0 || img->display.max_x != 6)
            out[0] = -1;
        n = 0;
    }
    nbt_image_free(img);
    nbt_image_free(img2);
    img = img2 = NULL;
    return n;
}


/* ---- numerics: quadratures, phase functions, photon counts, planners ---- */
static double vals[256];
static size_t nvals;
static size_t fin_vals(int ok, double *out)
{
    if (ok)
        memcpy(out, vals, nvals * sizeof *out);
    return ok ? nvals : 0;
}
static nbt_phase *ph;
static void setup_ph(void)
{
    ph = nbt_phase_hg2(0.7, -0.3, 0.8);
}
static void setup_hg(void)
{
    ph = nbt_phase_hg(0.6);
}
static size_t fin_ph_vals(int ok, double *out)
{
    nbt_phase_free(ph);
    ph = NULL;
    return fin_vals(ok, out);
}
static const nbt_airlight_geom ageo = {0.1, 0.25, 2.0, 5.0, 0.7, 8.0};
static nbt_status call_airlight_direct(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    nvals = 2;
    return nbt_airlight_direct(ph, &ageo, 1e-8, &vals[0], &vals[1]);
}
static nbt_status call_airlight_series(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    double b[12];
    nbt_status st = nbt_phase_moments(ph, 11, b);
    if (st != NBT_OK)
        return st;
    nvals = 2;
    return nbt_airlight_series(b, 12, &ageo, 1e-8, &vals[0], &vals[1]);
}
static nbt_status call_hk(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    nvals = 10;
    return nbt_hk(4, 1.3, -0.4, 1e-9, vals, vals + 5);
}
static const nbt_surface_geom sgeo = {0.1, 0.25, 2.0, 3.0, 0.4, 1.1, 0.6, 0.3, 8};
static nbt_status call_surface_series(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    double b[6];
    nbt_status st = nbt_phase_moments(ph, 5, b);
    if (st != NBT_OK)
        return st;
    nvals = 2;
    return nbt_surface_series(b, 6, &sgeo, 1e-6, &vals[0], &vals[1]);
}
static nbt_status call_jk(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    nvals = 8;
    return nbt_jk(3, 2, 0.8, 1.2, 1e-9, vals, vals + 4);
}
static void setup_j(void)
{
    nbt_axis a0 = {0, 3, NBT_AXIS_SQRT, 0, 5}, a1 = {0, 3.14159, NBT_AXIS_LINEAR, 0, 7};
    tab = nbt_table_alloc(NBT_TABLE_J, &a0, &a1, 2);
    tab->k[0] = 0, tab->k[1] = 3, tab->n = 2;
}
static nbt_status call_j(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    nbt_build_opts o = {1e-6, 1, 1};
    return nbt_j_table_build(tab, NULL, &o);
}
/* nbt_phase_parse of a tabulated file, then its moments */
static nbt_status call_phase_parse(char *err, size_t errlen)
{
    char spec[160];
    snprintf(spec, sizeof spec, "table:%s", path_txt);
    nbt_status st = nbt_phase_parse(spec, &ph, err, errlen);
    if (st != NBT_OK)
        return st;
    nvals = 6;
    for (int i = 0; i < 3; i++)
        vals[i] = nbt_phase_eval(ph, -0.9 + 0.8 * i);
    return nbt_phase_moments(ph, 2, vals + 3);
}
static size_t fin_mc(int ok, double *out);
static nbt_mc_result *mcr;
static nbt_status call_mc(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    static const double zp[2] = {0.5, 1.5};
    nbt_mc_config mc = {0};
    mc.sigma_t = 1.0, mc.albedo = 0.9, mc.phase = ph, mc.nplanes = 2, mc.z_planes = zp, mc.r_bins = 3;
    mc.r_max_scale = 0.8, mc.photons = 64, mc.seed = 3, mc.threads = 1;
    return nbt_mc_run(&mc, &mcr);
}
static size_t fin_mc(int ok, double *out)
{
    size_t n = 0;
    if (ok) {
        for (size_t i = 0; i < 6; i++)
            out[n++] = mcr->psi[i], out[n++] = mcr->psi_se[i];
        for (size_t i = 0; i < 2; i++)
            out[n++] = mcr->M0[i], out[n++] = mcr->M2[i];
    }
    nbt_mc_result_free(mcr);
    mcr = NULL;
    return n + fin_ph_vals(0, out);
}
static nbt_mc_kernel_result *mkr;
static nbt_status call_mc_kernel(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    static const double z[] = {1.5, 2.0}, edges[] = {0.02, 0.1, 0.4}, alb[] = {0.9, 0.5};
    nbt_mc_kernel_config cfg = {.phase = ph, .infinite = 1, .nplanes = 2, .z_planes = z, .nedges = 3,
                                .edges = edges, .nalbedo = 2, .albedo = alb, .photons = 64, .seed = 7, .threads = 1};
    return nbt_mc_kernel_run(&cfg, &mkr);
}
static size_t fin_mc_kernel(int ok, double *out)
{
    size_t n = 0;
    if (ok)
        for (size_t i = 0; i < 2 * 2 * 2 * 4; i++)
            out[n++] = mkr->mass[i], out[n++] = mkr->mass_se[i];
    nbt_mc_kernel_result_free(mkr);
    mkr = NULL;
    return n + fin_ph_vals(0, out);
}
/* a planned H set (orders 0..5: two packs) and a J^1 set, built */
static nbt_plan *plan;
static nbt_tableset tsets[2];
static nbt_status call_plan(char *err, size_t errlen)
{
    nbt_plan_request rq[2] = {{NBT_TABLE_H, 0, 6, NULL, 5.0, 0.0, {9, 5}, 0, 0},
                              {NBT_TABLE_J, 1, 2, NULL, 4.0, 0.0, {5, 9}, 0, 0}};
    return nbt_plan_tables(rq, 2, 1, &plan, err, errlen);
}
static size_t fin_plan(int ok, double *out)
{
    size_t n = 0;
    for (size_t i = 0; ok && i < nbt_plan_count(plan); i++) {
        const nbt_plan_set *ps = nbt_plan_get(plan, i);
        out[n++] = (double)ps->npacks, out[n++] = ps->pred_err, out[n++] = (double)ps->axis[0].n;
        out[n++] = (double)ps->axis[1].n, out[n++] = ps->axis[1].lo, out[n++] = ps->axis[1].hi;
    }
    nbt_plan_free(plan);
    plan = NULL;
    return n;
}
/* the sets of a plan made once beforehand (xplan, make_inputs), built armed */
static nbt_plan *xplan;
static nbt_status call_plan_exec(char *err, size_t errlen)
{
    return nbt_plan_execute_all(xplan, tsets, err, errlen);
}
static size_t fin_plan_exec(int ok, double *out)
{
    size_t n = 0;
    for (int i = 0; ok && i < 2; i++)
        for (size_t j = 0; j < tsets[i].count; j++)
            n += put_table(tsets[i].t[j], out + n);
    for (int i = 0; ok && i < 2; i++)
        nbt_tableset_free(&tsets[i]);
    return n;
}
/* a g-sliced J^1 table: planned once beforehand (the planner builds a 33 x 33 x 3 proxy), built armed */
static nbt_gslice_plan_t gplan;
/* the planner itself: its rule and the proxy build (33 x 33 x 3) that times it */
static nbt_gslice_plan_t gplan2;
static nbt_status call_gslice_plan(char *err, size_t errlen)
{
    nbt_gslice_request r = {NBT_TABLE_J, 1, 3.0, {-0.3, 0.6}, 0, {5, 9, 3}, 0};
    return nbt_gslice_plan(&r, 1, &gplan2, err, errlen);
}
static size_t fin_gslice_plan(int ok, double *out)
{
    size_t n = 0;
    for (int a = 0; ok && a < 3; a++)
        out[n++] = (double)gplan2.axis[a].n, out[n++] = gplan2.axis[a].lo, out[n++] = gplan2.axis[a].hi,
        out[n++] = gplan2.axis[a].c, out[n++] = gplan2.axis[a].map;
    if (ok)
        out[n++] = gplan2.bytes, out[n++] = gplan2.pred_err;
    return n;
}
static nbt_status call_gslice(char *err, size_t errlen)
{
    return nbt_gslice_execute(&gplan, 1, &tab, err, errlen);
}
/* raw grids: write, then read back */
static nbt_grid *grid;
static void setup_grid(void)
{
    const double o[3] = {-1, 0.5, 2};
    grid = nbt_grid_alloc(3, 2, 4, o, 0.25);
    for (size_t i = 0; i < 24; i++)
        grid->data[i] = (float)i * 0.5f;
    dir_base = dir_entries();
}
static nbt_status call_grid(char *err, size_t errlen)
{
    nbt_status st = nbt_grid_write_raw(grid, path_out, err, errlen);
    nbt_grid_free(grid);
    grid = NULL;
    if (st == NBT_OK)
        st = nbt_grid_read_raw(path_out, &grid, err, errlen);
    return st;
}
static size_t fin_grid(int ok, double *out)
{
    size_t n = 0;
    if (ok) {
        out[n++] = (double)grid->nx, out[n++] = (double)grid->ny, out[n++] = (double)grid->nz;
        out[n++] = grid->origin[0], out[n++] = grid->origin[2], out[n++] = grid->voxel;
        for (size_t i = 0; i < 24; i++)
            out[n++] = grid->data[i];
    } else if (dir_entries() != dir_base + (access(path_out, F_OK) == 0)) {
        printf("      grid_write_raw: a failed write left a file behind\n");
        out[n++] = -1;
    }
    nbt_grid_free(grid);
    grid = NULL;
    unlink(path_out);
    return n;
}
/* screen space: a 9 x 5 image with two depth layers and sky, FITTED kernel, layered (FFT) and brute force */
enum { SW = 9, SH = 5 };
static float srgb[SW * SH * 3], sD[SW * SH];
static double sS[SW * SH * 3], sT[SW * SH];
static nbt_status call_screen(int layered)
{
    nbt_screen_input in = {SW, SH, srgb, sD, 0.02, NULL};
    nbt_screen_kernel *k = nbt_screen_kernel_phase(NBT_SKERNEL_FITTED, 0.4, 0.8, ph, NBT_SCREEN_ENTERING, NULL);
    if (!k)
        return NBT_ENOMEM;
    nbt_status st = layered ? nbt_screen_layered(&in, k, NBT_SCREEN_NEAR, 1e-6, 4, 1, sS, sT)
                            : nbt_screen_brute(&in, k, NBT_SCREEN_SOURCE, 1e-6, 1, sS, sT);
    nbt_screen_kernel_free(k);
    nvals = 0;
    return st;
}
static nbt_status call_screen_layered(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    return call_screen(1);
}
static nbt_status call_screen_brute(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    return call_screen(0);
}
static size_t fin_screen(int ok, double *out)
{
    size_t n = 0;
    if (ok) {
        memcpy(out, sS, sizeof sS);
        memcpy(out + SW * SH * 3, sT, sizeof sT);
        n = SW * SH * 4;
    }
    return n + fin_ph_vals(0, out);
}


/* ---- the screen model container: alloc, set, write (armed); read back (armed) ---- */
static char path_model[128];
static nbt_screen_model *smodel;
static nbt_status make_model(void)
{
    static const double g[] = {0.5, 0.9}, alb[] = {0.6, 0.95}, tau[] = {0.5, 4.0};
    smodel = nbt_screen_model_alloc(NULL, 2, g, 2, alb, 2, tau);
    if (!smodel)
        return NBT_ENOMEM;
    for (int geo = 0; geo < 2; geo++)
        for (size_t ip = 0; ip < 2; ip++)
            for (size_t ia = 0; ia < 2; ia++)
                for (size_t it = 0; it < 2; it++) {
                    nbt_screen_shape sh;
                    memset(&sh, 0, sizeof sh);
                    double M = 0.01 * (1 + (double)ip) * (1 + 3 * (double)ia) * (1 + 7 * (double)it) * (1 + geo);
                    sh.erfc[10 + ip + 2 * it] = 0.75 * M, sh.gauss[20 + ia] = 0.25 * M;
                    nbt_status st = nbt_screen_model_set(smodel, (nbt_screen_geometry)geo, ip, ia, it, &sh);
                    if (st != NBT_OK)
                        return st;
                }
    return NBT_OK;
}
static void setup_model_write(void)
{
    dir_base = dir_entries();
}
static nbt_status call_model_write(char *err, size_t errlen)
{
    nbt_status st = make_model();
    if (st == NBT_OK)
        st = nbt_screen_model_write(smodel, path_out, "oom", err, errlen);
    return st;
}
/* the model evaluated (HG 0.7 between the nodes, both geometries) */
static size_t put_model(const nbt_screen_model *m, double *out)
{
    size_t n = 0;
    nbt_phase *p7 = nbt_phase_hg(0.7);
    for (int geo = 0; geo < 2; geo++) {
        nbt_screen_shape o;
        int ex = -1;
        nbt_screen_model_eval(m, p7, (nbt_screen_geometry)geo, 0.8, 1.5, &o, &ex);
        memcpy(out + n, o.erfc, sizeof o.erfc), n += NBT_SCREEN_NSLOTS;
        memcpy(out + n, o.gauss, sizeof o.gauss), n += NBT_SCREEN_NSLOTS;
        out[n++] = ex;
    }
    nbt_phase_free(p7);
    return n;
}
static size_t fin_model_write(int ok, double *out)
{
    size_t n = 0;
    nbt_screen_model_free(smodel);
    smodel = NULL;
    if (ok) {
        char e[256];
        if (nbt_screen_model_read(path_out, &smodel, e, sizeof e) == NBT_OK)
            n = put_model(smodel, out);
        nbt_screen_model_free(smodel);
        smodel = NULL;
    } else if (dir_entries() != dir_base) {
        printf("      screen_model_write: a failed write left a file behind\n");
        out[n++] = -1;
    }
    unlink(path_out);
    return n;
}
static nbt_status call_model_read(char *err, size_t errlen)
{
    return nbt_screen_model_read(path_model, &smodel, err, errlen);
}
static size_t fin_model_read(int ok, double *out)
{
    size_t n = ok ? put_model(smodel, out) : 0;
    nbt_screen_model_free(smodel);
    smodel = NULL;
    return n;
}
/* the text readers of the fitted kernel model and the kernel correction (fopen's
 * FILE is an allocation: its failure is ENOMEM, not EIO) */
static nbt_beam_fit bfit;
static nbt_kernel_correction kcorr;
static nbt_status call_beamfit_read(char *err, size_t errlen)
{
    return nbt_beam_fit_read(path_beamfit, &bfit, err, errlen);
}
static size_t fin_beamfit_read(int ok, double *out)
{
    size_t n = ok ? sizeof bfit.c / sizeof(double) : 0; /* every coefficient, both geometries */
    memcpy(out, bfit.c, n * sizeof *out);
    return n;
}
static nbt_status call_corr_read(char *err, size_t errlen)
{
    return nbt_kernel_correction_read(path_corr, &kcorr, err, errlen);
}
static size_t fin_corr_read(int ok, double *out)
{
    if (!ok)
        return 0;
    memcpy(out, kcorr.beta, sizeof kcorr.beta);
    memcpy(out + NBT_KERNEL_CORR_TERMS, kcorr.alpha, sizeof kcorr.alpha);
    return 2 * NBT_KERNEL_CORR_TERMS;
}
/* NNLS shape fit of radial masses */
static nbt_status call_shape_fit(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    static const double edges[] = {0.05, 0.2, 0.5, 1.0, 2.0}, mass[] = {0.02, 0.05, 0.06, 0.04, 0.02, 0.005};
    nbt_screen_shape sh;
    nbt_status st = nbt_screen_shape_fit(5, edges, mass, NULL, 2, &sh, &vals[0]);
    nvals = 1;
    for (int i = 0; i < NBT_SCREEN_NSLOTS; i++)
        vals[nvals++] = sh.erfc[i] + 2 * sh.gauss[i];
    return st;
}
/* H tables: a set of two packs with the fixed phase and the Legendre orders, then the airlight from them */
static nbt_table *hset[2];
static void setup_hset(void)
{
    nbt_axis a0 = {0, 12, NBT_AXIS_SQRT, 0, 9}, a1 = {-1.5707963267948966, 1.5707963267948966, NBT_AXIS_COS, 0, 7};
    for (int i = 0; i < 2; i++) {
        hset[i] = nbt_table_alloc(NBT_TABLE_H, &a0, &a1, 4);
        for (int c = 0; c < 4; c++)
            hset[i]->k[c] = 4 * i + c;
    }
    ph = nbt_phase_hg(0.4);
}
static nbt_status call_hset(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    nbt_build_opts o = {1e-6, 1, 1};
    nbt_status st = nbt_h_table_build_set(hset, 2, NULL, &o);
    double b[8];
    if (st == NBT_OK)
        st = nbt_phase_moments(ph, 7, b);
    if (st == NBT_OK) {
        const nbt_table *const tp[2] = {hset[0], hset[1]};
        st = nbt_airlight_table_e(tp, 2, b, 8, ph, &ageo, &vals[0], &vals[1]);
        if (st == NBT_ETOL)
            st = NBT_OK;
    }
    nvals = 2;
    return st;
}
static size_t fin_hset(int ok, double *out)
{
    size_t n = 0;
    for (int i = 0; i < 2; i++) {
        if (ok)
            n += put_table(hset[i], out + n);
        nbt_table_free(hset[i]);
        hset[i] = NULL;
    }
    if (ok)
        out[n++] = vals[0], out[n++] = vals[1];
    return n + fin_ph_vals(0, out);
}


/* ---- the path-traced screen reference on the 9 x 5 image (4 spp, one pass) ---- */
static float sZ[SW * SH];
static double sse[SW * SH * 3];
static nbt_status call_screen_path(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    nbt_screen_world w = {SW, SH, srgb, sZ, 0.1, 4.3, 2.2, 1, 0, SW - 2, SH};
    nbt_screen_path_medium m = {.sigma_t = {1, 0.5, 2}, .albedo = {0.9, 0.7, 0.5}, .phase = ph, .radius = INFINITY};
    nbt_screen_path_opts o = {.spp = 4, .seed = 1, .nthreads = 1};
    unsigned long done = 0;
    memset(sS, 0, sizeof sS);
    nbt_status st = nbt_screen_path(&w, &m, &o, sS, sse, &done);
    vals[0] = (double)done;
    return st;
}
static size_t fin_screen_path(int ok, double *out)
{
    size_t n = 0;
    if (ok) {
        memcpy(out, sS, sizeof sS);
        memcpy(out + SW * SH * 3, sse, sizeof sse);
        n = SW * SH * 6;
        out[n++] = vals[0];
    }
    return n + fin_ph_vals(0, out);
}
/* per-pixel moment kernels through a layered density (beam.c's layered moments) */
static double slab_rho(const double q[3], void *ctx)
{
    (void)ctx;
    return q[2] > 0.5 ? 2.0 : 0.5;
}
static nbt_screen_pixkern spix[SW * SH];
static nbt_status call_medium_kernels(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    static const double z[2] = {0, 1.5}, rho[2] = {1, 0.25};
    nbt_beam_medium m = nbt_beam_homogeneous(0.8, 0.9, 0.05);
    m.nlayers = 2, m.z = z, m.rho = rho;
    nbt_screen_input in = {SW, SH, srgb, sD, 0.02, NULL};
    nbt_camera cam = {{0, 0, 0}, {0, 0.2, 1}, {0, 1, 0}};
    double me = 0;
    nbt_status st = nbt_screen_medium_kernels(&in, &m, slab_rho, NULL, &cam, 0.25, NULL, 1, spix, &me);
    nvals = 0;
    for (size_t i = 0; i < SW * SH; i++)
        vals[nvals++] = spix[i].T + 3 * spix[i].M0 + 7 * spix[i].beta_px;
    vals[nvals++] = me;
    return st;
}
/* Psi of a two-layer medium by the line integral and Ishimaru's moments */
static nbt_status call_beam_psi(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    static const double z[2] = {0, 0.7}, rho[2] = {1, 3};
    nbt_beam_medium m = nbt_beam_homogeneous(1.2, 0.8, 0.08);
    m.nlayers = 2, m.z = z, m.rho = rho;
    nvals = 6;
    nbt_status st = nbt_beam_psi(&m, NBT_PSI_LINEINT, 1.3, 0.2, &vals[0], &vals[1]);
    if (st == NBT_OK)
        st = nbt_beam_psi(&m, NBT_PSI_ISHIMARU, 1.3, 0.2, &vals[2], &vals[3]);
    if (st == NBT_OK)
        st = nbt_beam_moments(&m, NBT_BEAM_SMALLANGLE, 1.1, &vals[4], &vals[5], &vals[5]);
    return st;
}


/* an RGB kernel (moment kernels, a sigma_t per channel), the brute-force operator and its
 * scores against a made-up reference */
static double cref[SW * SH * 3];
static void setup_compare(void)
{
    for (size_t i = 0; i < SW * SH * 3; i++)
        cref[i] = 0.01 * (double)(i % 13) + 0.002 * (double)i;
}
static nbt_status call_compare(char *err, size_t errlen)
{
    (void)err, (void)errlen;
    nbt_screen_input in = {SW, SH, srgb, sD, 0.02, NULL};
    nbt_beam_medium mr = nbt_beam_homogeneous(0.3, 0.8, 0.05), mg = mr, mb = mr;
    mg.sigma_t = 0.5, mb.sigma_t = 0.9;
    nbt_screen_kernel *r = nbt_screen_kernel_alloc(NBT_SKERNEL_MOMENT, &mr, NULL),
                      *g = nbt_screen_kernel_alloc(NBT_SKERNEL_MOMENT, &mg, NULL),
                      *b = nbt_screen_kernel_alloc(NBT_SKERNEL_MOMENT, &mb, NULL);
    if (!r || !g || !b) {
        nbt_screen_kernel_free(r), nbt_screen_kernel_free(g), nbt_screen_kernel_free(b);
        return NBT_ENOMEM;
    }
    nbt_screen_kernel *k = nbt_screen_kernel_rgb(r, g, b); /* takes r, g, b, also on failure */
    if (!k)
        return NBT_ENOMEM;
    nbt_screen_metrics m = {0};
    nbt_status st = nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, 1e-6, 1, sS, sT);
    if (st == NBT_OK)
        st = nbt_screen_compare(&in, k, sS, cref, &m);
    nbt_screen_kernel_free(k);
    nvals = 6;
    vals[0] = m.rel_l1, vals[1] = m.rel_rms, vals[2] = m.edge, vals[3] = m.bias, vals[4] = m.max;
    vals[5] = (double)m.edge_pixels;
    return st;
}
static size_t fin_compare(int ok, double *out)
{
    size_t n = 0;
    if (ok) {
        memcpy(out, sS, sizeof sS);
        memcpy(out + SW * SH * 3, sT, sizeof sT);
        n = SW * SH * 4;
    }
    if (ok)
        memcpy(out + n, vals, nvals * sizeof *out), n += nvals;
    return n;
}

/* inputs written once, unarmed */
static int make_inputs(void)
{
    snprintf(dir, sizeof dir, "%s", "/tmp/nbt-oom-XXXXXX");
    if (!mkdtemp(dir))
        return -1;
    snprintf(path_tab, sizeof path_tab, "%s/tab.exr", dir);
    snprintf(path_img, sizeof path_img, "%s/img.exr", dir);
    snprintf(path_out, sizeof path_out, "%s/out.exr", dir);
    snprintf(path_txt, sizeof path_txt, "%s/phase.txt", dir);
    snprintf(path_model, sizeof path_model, "%s/model.txt", dir);
    snprintf(path_beamfit, sizeof path_beamfit, "%s/beamfit.txt", dir);
    snprintf(path_corr, sizeof path_corr, "%s/corr.txt", dir);
    setup_tab_write();
    nbt_status st = nbt_table_write_exr(tab, path_tab, NBT_EXR_ZIP);
    nbt_table_free(tab);
    tab = NULL;
    if (st != NBT_OK)
        return -1;
    /* a 7 x 5 image off the origin, with a named RGB layer and depth, two extra layers and an attribute */
    nbt_image *im = nbt_image_alloc(7, 5, 1);
    for (size_t i = 0; i < 7 * 5 * 3; i++)
        im->rgb[i] = (float)(0.1 * (double)i - 1.0), lay_data[i] = (float)(i % 11) * 0.5f;
    for (size_t i = 0; i < 7 * 5; i++)
        im->z[i] = (float)(2.0 + (double)i), one_data[i] = (float)i / 8.0f;
    im->x0 = -3, im->y0 = 2;
    im->display = (nbt_box2i){-2, 3, 2, 5};
    im->rgb_layer = strdup("ViewLayer.Combined");
    im->z_name = strdup("ViewLayer.Depth.Z");
    nbt_image_layer ly[2] = {{"T", 3, lay_ch, lay_data}, {"offscreen", 1, one_ch, one_data}};
    static const char *const attrs[] = {"owner", "oom", "nbt.note", "kept"};
    nbt_exr_write_opts o = {.layers = ly, .nlayers = 2, .attrs = attrs, .nattrs = 2};
    char e[256];
    st = nbt_image_write_exr_ex(im, path_img, &o, e, sizeof e);
    nbt_image_free(im);
    if (st != NBT_OK) {
        printf("writing %s: %s\n", path_img, e);
        return -1;
    }
    for (size_t i = 0; i < SW * SH; i++) { /* near layer at 2.5 on the left, far at 7 on the right, sky top right */
        size_t x = i % SW, y = i / SW;
        sD[i] = x < 4 ? 2.5f : (x > 6 && y < 2) ? INFINITY : 7.0f;
        sZ[i] = x < 4 ? 2.0f : (x > 6 && y < 2) ? INFINITY : 5.5f;
        for (int c = 0; c < 3; c++)
            srgb[3 * i + c] = (float)(0.2 + 0.1 * c + 0.05 * (double)x - 0.03 * (double)y);
    }
    nbt_plan_request rq[2] = {{NBT_TABLE_H, 0, 6, NULL, 5.0, 0.0, {9, 5}, 0, 0},
                              {NBT_TABLE_J, 1, 2, NULL, 4.0, 0.0, {5, 9}, 0, 0}};
    nbt_gslice_request gr = {NBT_TABLE_J, 1, 3.0, {-0.3, 0.6}, 0, {5, 9, 3}, 0};
    if (nbt_plan_tables(rq, 2, 1, &xplan, e, sizeof e) != NBT_OK || nbt_gslice_plan(&gr, 1, &gplan, e, sizeof e) != NBT_OK) {
        printf("planning: %s\n", e);
        return -1;
    }
    if (make_model() != NBT_OK || nbt_screen_model_write(smodel, path_model, "oom", e, sizeof e) != NBT_OK)
        return -1;
    nbt_screen_model_free(smodel);
    smodel = NULL;
    FILE *f = fopen(path_txt, "w");
    if (!f)
        return -1;
    fprintf(f, "# mu p\n-1 0.2\n-0.25 0.5\n0.5 1.5\n1 4\n");
    fclose(f);
    /* the two text readers' inputs: libnbt's default beam model as nbt-fit writes it, and a
     * kernel correction with asymmetric coefficients */
    if (!(f = fopen(path_beamfit, "w")) || nbt_beam_fit_fprint(f, nbt_beam_fit_default(), "# oom\n") != NBT_OK)
        return -1;
    fclose(f);
    if (!(f = fopen(path_corr, "w")))
        return -1;
    fprintf(f, "# correction\nbeta 0.1 -0.02 0.003 0.04 -0.005 0.06 -0.007\nalpha -0.3 0.01 0 0.2 0.02 -0.1 0.005\n");
    fclose(f);
    return 0;
}

int main(void)
{
    nbt_set_error_handler(on_error);
    dl_iterate_phdr(find_fftw, NULL);
    if (getenv("OOM_TRACE")) {
        void *bt[4];
        trace = backtrace(bt, 4) > 0; /* loads libgcc's unwinder before any arming */
    }
    printf("test_oom: injecting allocation failures\n"); /* stdout's buffer is allocated before any arming */
    if (make_inputs() != 0) {
        printf("FAIL: cannot write the inputs in %s\n", dir);
        return 1;
    }
    static const oom_case cases[] = {
        {"table_alloc3+dup", 0, NULL, call_table_dup, fin_table, 0},
        {"h_table_build", 1, setup_h, call_h, fin_table, 0},
        {"table_write_exr", 1, setup_tab_write, call_tab_write, fin_tab_write, 0},
        {"table_read_exr", 2, NULL, call_tab_read, fin_table, 0},
        {"image_read_exr", 2, NULL, call_img_read, fin_img, 0},
        {"image_write_exr_ex", 2, setup_img_write, call_img_write, fin_img_write, 0},
        {"image_copy_meta", 0, setup_copy_meta, call_copy_meta, fin_copy_meta, 0},
        {"airlight_direct", 1, setup_ph, call_airlight_direct, fin_ph_vals, 0},
        {"phase_moments+airlight_series", 1, setup_ph, call_airlight_series, fin_ph_vals, 0},
        {"hk", 1, NULL, call_hk, fin_vals, 0},
        {"phase_moments+surface_series", 1, setup_ph, call_surface_series, fin_ph_vals, 0},
        {"jk", 1, NULL, call_jk, fin_vals, 0},
        {"j_table_build", 1, setup_j, call_j, fin_table, 0},
        {"phase_parse(table:)+moments", 1, NULL, call_phase_parse, fin_ph_vals, 0},
        {"mc_run", 1, setup_ph, call_mc, fin_mc, 0},
        {"mc_kernel_run", 1, setup_ph, call_mc_kernel, fin_mc_kernel, 0},
        {"plan_tables", 2, NULL, call_plan, fin_plan, 0},
        {"plan_execute_all", 2, NULL, call_plan_exec, fin_plan_exec, 0},
        {"gslice_plan", 2, NULL, call_gslice_plan, fin_gslice_plan, 0},
        {"gslice_execute", 2, NULL, call_gslice, fin_table, 0},
        {"grid_write_raw+read_raw", 2, setup_grid, call_grid, fin_grid, 0},
        {"screen_model_alloc+set+write", 1, setup_model_write, call_model_write, fin_model_write, 0},
        {"screen_model_read", 2, NULL, call_model_read, fin_model_read, 0},
        {"beam_fit_read", 2, NULL, call_beamfit_read, fin_beamfit_read, 0},
        {"kernel_correction_read", 2, NULL, call_corr_read, fin_corr_read, 0},
        {"screen_shape_fit", 1, NULL, call_shape_fit, fin_vals, 0},
        {"h_table_build_set+airlight_table_e", 1, setup_hset, call_hset, fin_hset, 0},
        {"screen_path", 1, setup_hg, call_screen_path, fin_screen_path, 0},
        {"screen_medium_kernels", 1, NULL, call_medium_kernels, fin_vals, 0},
        {"beam_psi+beam_moments", 1, NULL, call_beam_psi, fin_vals, 0},
        {"screen_kernel_rgb+brute+compare", 1, setup_compare, call_compare, fin_compare, 0},
        {"screen_kernel_phase+layered", 1, setup_hg, call_screen_layered, fin_screen, 1},
        {"screen_kernel_phase+brute", 1, setup_hg, call_screen_brute, fin_screen, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        run_case(&cases[i]);
    nbt_plan_free(xplan);
    unlink(path_model);
    unlink(path_tab), unlink(path_img), unlink(path_txt), unlink(path_out), unlink(path_beamfit), unlink(path_corr);
    rmdir(dir);
    return t_done();
}
#endif
