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
 *   - the reason (err buffer or the error handler's) says "memory";
 *   - nothing leaks: the live allocation count after the call (and after
 *     freeing what the caller owns) equals the count before it;
 *   - a call that succeeds (with no failure injected, or one the code
 *     recovered from) gives bit for bit the result of a reference call
 *     made without injection, so a mutant in the success path shows too.
 * Every call runs with one thread: the k-th allocation is then the same one
 * on every run.
 *
 * ASan (configure --enable-sanitizers) replaces malloc itself, so the
 * injector cannot work there: the test then exits 77 (SKIP). */
#include <config.h>
#include <dirent.h>
#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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

static int inject(void)
{
    if (!atomic_load(&armed))
        return 0;
    if (atomic_fetch_sub(&countdown, 1) == 1) {
        atomic_fetch_add(&injected, 1);
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
        return malloc(n);
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
    return memalign(al, n);
}

int posix_memalign(void **out, size_t al, size_t n)
{
    void *p = memalign(al, n);
    if (!p)
        return ENOMEM;
    *out = p;
    return 0;
}

void *valloc(size_t n)
{
    return memalign((size_t)sysconf(_SC_PAGESIZE), n);
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
    int msg;                            /* an injected failure must come with a reason saying "memory" */
    void (*setup)(void);                /* unarmed: inputs the call needs (may be NULL) */
    nbt_status (*call)(char *err, size_t errlen); /* the call under test; NBT_ENOMEM for a NULL constructor result */
    size_t (*finish)(int ok, double *out); /* unarmed: copy the result (ok) to out, return its length; free
                                              what the caller owns */
} oom_case;

static int says_memory(const char *s)
{
    return strstr(s, "memory") != NULL;
}

static void run_case(const oom_case *c)
{
    char err[512];
    long live0 = atomic_load(&live);
    if (c->setup)
        c->setup();
    nbt_status st = c->call(err, sizeof err);
    size_t nref = c->finish(st == NBT_OK, ref);
    if (st != NBT_OK || atomic_load(&live) != live0) {
        t_true(0, "%s: reference call (status %d, %ld allocations left)", c->name, st, atomic_load(&live) - live0);
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
                    printf("      %s: k = %ld: status %d (%s) with %d failures injected, want NBT_ENOMEM\n",
                           c->name, k, st, nbt_strerror(st), inj);
            } else if (c->msg && !says_memory(err) && !says_memory(reason)) {
                if (bad_msg++ < 3)
                    printf("      %s: k = %ld: reason \"%s\" / \"%s\" does not say memory\n", c->name, k, err,
                           reason);
            }
        }
    }
    t_true(k <= K_MAX && !bad_status && !bad_msg && !leaks && !differs,
           "%s: %ld allocations, %ld failures caught, %ld recovered, result bitwise equal", c->name, k - 1, nfail,
           nrecover);
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
static char dir[64], path_tab[128], path_img[128], path_out[128], path_txt[128];

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
    FILE *f = fopen(path_txt, "w");
    if (!f)
        return -1;
    fprintf(f, "# mu p\n-1 0.2\n-0.25 0.5\n0.5 1.5\n1 4\n");
    fclose(f);
    return 0;
}

int main(void)
{
    nbt_set_error_handler(on_error);
    printf("test_oom: injecting allocation failures\n"); /* stdout's buffer is allocated before any arming */
    if (make_inputs() != 0) {
        printf("FAIL: cannot write the inputs in %s\n", dir);
        return 1;
    }
    static const oom_case cases[] = {
        {"table_alloc3+dup", 0, NULL, call_table_dup, fin_table},
        {"h_table_build", 1, setup_h, call_h, fin_table},
        {"table_write_exr", 1, setup_tab_write, call_tab_write, fin_tab_write},
        {"table_read_exr", 1, NULL, call_tab_read, fin_table},
        {"image_read_exr", 1, NULL, call_img_read, fin_img},
        {"image_write_exr_ex", 1, setup_img_write, call_img_write, fin_img_write},
        {"image_copy_meta", 0, setup_copy_meta, call_copy_meta, fin_copy_meta},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        run_case(&cases[i]);
    unlink(path_tab), unlink(path_img), unlink(path_txt), unlink(path_out);
    rmdir(dir);
    return t_done();
}
#endif
