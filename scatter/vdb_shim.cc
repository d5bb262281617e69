// scatter/vdb_shim.cc: the C interface of scatter/vdb_shim.h over OpenVDB
// (Debian 12: OpenVDB 10). Cell-centred convention: index (i,j,k) is a voxel
// centre, world = transform.indexToWorld(i,j,k).
#include <config.h>
#include <sys/stat.h>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <mutex>
#include <new>
#include <string>
#include <openvdb/openvdb.h>
#include "vdb_shim.h"

namespace {

std::once_flag init_once;

void init()
{
    std::call_once(init_once, [] { openvdb::initialize(); });
}

__attribute__((format(printf, 3, 4))) void fail(char *err, size_t errlen, const char *fmt, ...)
{
    if (!err || errlen == 0)
        return;
    va_list ap;
    va_start(ap, fmt);
    std::vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
    for (char *c = err; *c; c++) // one line, whatever the library said
        if (*c == '\n' || *c == '\r')
            *c = ' ';
}

// "" when the file can be opened for reading, else the reason (strerror text;
// strerror_r, the GNU form that g++ selects, as strerror is not thread-safe)
std::string unreadable(const char *path)
{
    char buf[128];
    struct stat st;
    if (stat(path, &st) != 0)
        return strerror_r(errno, buf, sizeof buf);
    if (S_ISDIR(st.st_mode))
        return strerror_r(EISDIR, buf, sizeof buf);
    std::FILE *f = std::fopen(path, "rb");
    if (!f)
        return strerror_r(errno, buf, sizeof buf);
    std::fclose(f);
    return "";
}

// "a (float), b (double)" or "no grids"
std::string grid_list(const openvdb::GridPtrVec &grids)
{
    std::string s;
    for (const auto &g : grids) {
        if (!s.empty())
            s += ", ";
        s += g->getName() + " (" + g->valueType() + ")";
    }
    return s.empty() ? "no grids" : "grids: " + s;
}

// Accept only world = s * index + t with s > 0 (up to a relative 1e-9 in
// the 3x3 part). On success *s and t[] are set; else a message is written.
bool uniform_transform(const openvdb::math::Transform &xf, double *s, double t[3], const char *gname,
                       const char *path, char *err, size_t errlen)
{
    if (!xf.isLinear()) {
        fail(err, errlen, "grid \"%s\" in %s has a non-linear (%s) transform: only a uniform scale plus translation is "
             "accepted", gname, path, xf.mapType().c_str());
        return false;
    }
    const openvdb::math::Mat4d m = xf.baseMap()->getAffineMap()->getMat4();
    const double d = m[0][0], tol = 1e-9 * std::fabs(d);
    bool ok = std::isfinite(d) && d > 0;
    for (int r = 0; r < 4 && ok; r++)
        for (int c = 0; c < 4 && ok; c++)
            ok = std::isfinite(m[r][c]);
    for (int r = 0; r < 3 && ok; r++)
        for (int c = 0; c < 3 && ok; c++)
            ok = std::fabs(m[r][c] - (r == c ? d : 0.0)) <= tol;
    if (!ok) {
        const openvdb::Vec3d v = xf.voxelSize();
        if (std::fabs(v[0] - v[1]) > 1e-9 * v[0] || std::fabs(v[0] - v[2]) > 1e-9 * v[0])
            fail(err, errlen, "grid \"%s\" in %s has non-uniform voxels (%g x %g x %g): only a uniform scale plus "
                 "translation is accepted", gname, path, v[0], v[1], v[2]);
        else
            fail(err, errlen, "grid \"%s\" in %s has a rotated, sheared or mirrored transform: only a uniform scale "
                 "plus translation is accepted", gname, path);
        return false;
    }
    *s = d;
    for (int c = 0; c < 3; c++)
        t[c] = m[3][c];
    return true;
}

int read_grid(const char *path, const char *name, size_t max_voxels, nbt_vdb_grid *out, char *err, size_t errlen)
{
    openvdb::io::File file(path);
    file.open(false); // no delayed loading: read everything now, keep no mapping
    openvdb::GridPtrVecPtr meta = file.readAllGridMetadata();
    openvdb::GridBase::Ptr chosen;
    const char *want = name ? name : "density";
    for (const auto &g : *meta)
        if (g->getName() == want) {
            chosen = g;
            break;
        }
    if (!chosen && !name) { // no "density": the only float grid, if there is exactly one
        size_t nfloat = 0;
        for (const auto &g : *meta)
            if (g->isType<openvdb::FloatGrid>()) {
                chosen = g;
                nfloat++;
            }
        if (nfloat != 1) {
            fail(err, errlen, "%s has no grid named \"density\" and %zu float grids: name the grid to read (%s)", path,
                 nfloat, grid_list(*meta).c_str());
            file.close();
            return -1;
        }
    }
    if (!chosen) {
        fail(err, errlen, "%s has no grid named \"%s\" (%s)", path, name, grid_list(*meta).c_str());
        file.close();
        return -1;
    }
    const std::string gname = chosen->getName();
    if (!chosen->isType<openvdb::FloatGrid>()) {
        fail(err, errlen, "grid \"%s\" in %s holds %s values (%s), not float", gname.c_str(), path,
             chosen->valueType().c_str(), chosen->type().c_str());
        file.close();
        return -1;
    }
    openvdb::FloatGrid::Ptr grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(gname));
    file.close();
    if (!grid) {
        fail(err, errlen, "grid \"%s\" in %s could not be read as a float grid", gname.c_str(), path);
        return -1;
    }

    double s, t[3];
    if (!uniform_transform(grid->transform(), &s, t, gname.c_str(), path, err, errlen))
        return -1;
    if (grid->activeVoxelCount() == 0) {
        fail(err, errlen, "grid \"%s\" in %s is empty (no active voxels)", gname.c_str(), path);
        return -1;
    }
    const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    const openvdb::Coord lo = box.min(), hi = box.max();
    // int64: a box may span the whole int32 index range
    const uint64_t nx = (uint64_t)((int64_t)hi.x() - lo.x() + 1), ny = (uint64_t)((int64_t)hi.y() - lo.y() + 1),
                   nz = (uint64_t)((int64_t)hi.z() - lo.z() + 1);
    const long double total = (long double)nx * ny * nz; // exact enough to compare with a limit
    if (total > (long double)max_voxels || total * sizeof(float) > (long double)SIZE_MAX) {
        fail(err, errlen, "grid \"%s\" in %s: its dense box %llu x %llu x %llu = %.0Lf voxels exceeds the limit of %zu",
             gname.c_str(), path, (unsigned long long)nx, (unsigned long long)ny, (unsigned long long)nz, total,
             max_voxels);
        return -1;
    }
    const size_t n = (size_t)nx * ny * nz;
    float *data = static_cast<float *>(std::malloc(n * sizeof(float)));
    if (!data) {
        fail(err, errlen, "grid \"%s\" in %s: out of memory for %zu voxels", gname.c_str(), path, n);
        return -1;
    }
    const float bg = grid->background();
    for (size_t q = 0; q < n; q++)
        data[q] = bg;
    auto at = [&](const openvdb::Coord &c) -> float & {
        return data[((size_t)(c.z() - lo.z()) * ny + (size_t)(c.y() - lo.y())) * nx + (size_t)(c.x() - lo.x())];
    };
    for (auto it = grid->cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) {
            at(it.getCoord()) = *it;
        } else { // an active tile: every voxel it covers holds its value
            openvdb::CoordBBox tb;
            it.getBoundingBox(tb);
            tb.intersect(box);
            for (int z = tb.min().z(); z <= tb.max().z(); z++)
                for (int y = tb.min().y(); y <= tb.max().y(); y++)
                    for (int x = tb.min().x(); x <= tb.max().x(); x++)
                        at(openvdb::Coord(x, y, z)) = *it;
        }
    }
    for (size_t q = 0; q < n; q++)
        if (!std::isfinite(data[q]) || data[q] < 0) {
            const size_t i = q % nx, j = (q / nx) % ny, k = q / nx / ny;
            fail(err, errlen, "grid \"%s\" in %s: voxel (%zu,%zu,%zu) (index %lld,%lld,%lld) is %g: densities must be "
                 "finite and >= 0", gname.c_str(), path, i, j, k, (long long)lo.x() + (long long)i,
                 (long long)lo.y() + (long long)j, (long long)lo.z() + (long long)k, (double)data[q]);
            std::free(data);
            return -1;
        }
    out->nx = (size_t)nx;
    out->ny = (size_t)ny;
    out->nz = (size_t)nz;
    out->voxel = s;
    out->origin[0] = s * lo.x() + t[0]; // = indexToWorld(lo): centre of the box's first voxel
    out->origin[1] = s * lo.y() + t[1];
    out->origin[2] = s * lo.z() + t[2];
    out->data = data;
    return 0;
}

template <typename GridT>
typename GridT::Ptr dense_to_grid(const nbt_vdb_grid *g, const int i0[3])
{
    using V = typename GridT::ValueType;
    typename GridT::Ptr grid = GridT::create(V(0));
    typename GridT::Accessor acc = grid->getAccessor();
    for (size_t k = 0; k < g->nz; k++)
        for (size_t j = 0; j < g->ny; j++)
            for (size_t i = 0; i < g->nx; i++) {
                const float v = g->data[(k * g->ny + j) * g->nx + i];
                if (v != 0) // NaN too: only zeros stay inactive background
                    acc.setValue(openvdb::Coord(i0[0] + (int)i, i0[1] + (int)j, i0[2] + (int)k), V(v));
            }
    grid->tree().prune(); // constant blocks become tiles (lossless: zero tolerance)
    return grid;
}

int write_grids(const char *path, const nbt_vdb_test_grid *grids, size_t n, char *err, size_t errlen)
{
    openvdb::GridPtrVec out;
    for (size_t q = 0; q < n; q++) {
        const nbt_vdb_test_grid &e = grids[q];
        const nbt_vdb_grid *g = e.g;
        if (!e.name || !*e.name || !g || !g->data || g->nx == 0 || g->ny == 0 || g->nz == 0) {
            fail(err, errlen, "grid %zu: need a name and a non-empty grid with data", q);
            return -1;
        }
        if (!(g->voxel > 0) || !std::isfinite(g->voxel) || !std::isfinite(g->origin[0]) ||
            !std::isfinite(g->origin[1]) || !std::isfinite(g->origin[2])) {
            fail(err, errlen, "grid \"%s\": voxel size must be finite and > 0 and the origin finite", e.name);
            return -1;
        }
        const size_t dims[3] = {g->nx, g->ny, g->nz};
        for (int a = 0; a < 3; a++)
            if (dims[a] > (size_t)INT_MAX || (long long)e.index0[a] + (long long)dims[a] - 1 > INT_MAX) {
                fail(err, errlen, "grid \"%s\": %zu voxels from index %d do not fit OpenVDB's int32 coordinates",
                     e.name, dims[a], e.index0[a]);
                return -1;
            }
        // world = index * A + t (OpenVDB's row-vector convention), with voxel index0's centre at g->origin
        const double s = g->voxel;
        openvdb::math::Mat4d A = openvdb::math::Mat4d::identity();
        A[0][0] = A[1][1] = A[2][2] = s;
        if (e.transform == NBT_VDB_TEST_NONUNIFORM) {
            A[0][0] = 2 * s;
        } else if (e.transform == NBT_VDB_TEST_ROTATED) {
            const double c = std::cos(M_PI / 6), sn = std::sin(M_PI / 6);
            A[0][0] = s * c;
            A[0][1] = s * sn;
            A[1][0] = -s * sn;
            A[1][1] = s * c;
        }
        openvdb::Vec3d t;
        for (int c = 0; c < 3; c++)
            t[c] = g->origin[c] - (e.index0[0] * A[0][c] + e.index0[1] * A[1][c] + e.index0[2] * A[2][c]);
        openvdb::math::Transform::Ptr xf;
        if (e.transform == NBT_VDB_TEST_UNIFORM) {
            xf = openvdb::math::Transform::createLinearTransform(s);
            xf->postTranslate(t);
        } else {
            A.setTranslation(t);
            xf = openvdb::math::Transform::createLinearTransform(A);
        }
        openvdb::GridBase::Ptr grid;
        if (e.as_double)
            grid = dense_to_grid<openvdb::DoubleGrid>(g, e.index0);
        else
            grid = dense_to_grid<openvdb::FloatGrid>(g, e.index0);
        grid->setName(e.name);
        grid->setTransform(xf);
        grid->setGridClass(openvdb::GRID_FOG_VOLUME);
        out.push_back(grid);
    }
    openvdb::io::File file(path);
    file.write(out);
    file.close();
    return 0;
}

} // namespace

extern "C" int nbt_vdb_read(const char *path, const char *name, size_t max_voxels, nbt_vdb_grid *out, char *err,
                            size_t errlen)
{
    if (out)
        std::memset(out, 0, sizeof *out);
    if (!path || !out) {
        fail(err, errlen, "nbt_vdb_read: need a path and an output grid");
        return -1;
    }
    const std::string why = unreadable(path);
    if (!why.empty()) {
        fail(err, errlen, "%s: %s", path, why.c_str());
        return -1;
    }
    try {
        init();
        return read_grid(path, name, max_voxels, out, err, errlen);
    } catch (const std::bad_alloc &) {
        fail(err, errlen, "%s: out of memory", path);
    } catch (const std::exception &e) {
        fail(err, errlen, "%s: %s", path, e.what());
    } catch (...) {
        fail(err, errlen, "%s: unknown C++ exception", path);
    }
    return -1;
}

extern "C" void nbt_vdb_grid_free(nbt_vdb_grid *g)
{
    if (!g)
        return;
    std::free(g->data);
    std::memset(g, 0, sizeof *g);
}

extern "C" int nbt_vdb_write_test(const char *path, const nbt_vdb_test_grid *grids, size_t n, char *err,
                                  size_t errlen)
{
    if (!path || (!grids && n > 0)) {
        fail(err, errlen, "nbt_vdb_write: need a path and grids");
        return -1;
    }
    try {
        init();
        return write_grids(path, grids, n, err, errlen);
    } catch (const std::bad_alloc &) {
        fail(err, errlen, "%s: out of memory", path);
    } catch (const std::exception &e) {
        fail(err, errlen, "%s: %s", path, e.what());
    } catch (...) {
        fail(err, errlen, "%s: unknown C++ exception", path);
    }
    return -1;
}

extern "C" int nbt_vdb_write(const char *path, const char *name, const nbt_vdb_grid *g, char *err, size_t errlen)
{
    nbt_vdb_test_grid e;
    std::memset(&e, 0, sizeof e);
    e.name = name;
    e.g = g;
    e.transform = NBT_VDB_TEST_UNIFORM;
    return nbt_vdb_write_test(path, &e, 1, err, errlen);
}

extern "C" long nbt_vdb_test_active_tiles(const char *path, const char *name)
{
    if (!path || !name || !unreadable(path).empty())
        return -1;
    try {
        init();
        openvdb::io::File file(path);
        file.open(false);
        openvdb::GridBase::Ptr g = file.readGrid(name);
        file.close();
        openvdb::FloatGrid::Ptr f = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
        return f ? (long)f->tree().activeTileCount() : -1;
    } catch (...) {
        return -1;
    }
}
