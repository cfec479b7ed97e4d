// osd_eval: limit points of a Catmull-Clark control mesh, computed by OpenSubdiv's Bfr (or
// its Far, with -far), for tests/osd_compare.rs (which runs it through tests/osd.rs).
//
// Build: g++ -O2 -std=c++14 osd_eval.cpp -o osd_eval -losdCPU   (Debian: libosd-dev)
//
// Input on stdin, one item per line (blank lines are skipped), in this order:
//
//   boundary edge-and-corner|edge-only     Sdc VTX_BOUNDARY_EDGE_AND_CORNER / _EDGE_ONLY
//   creasing normal|chaikin                Sdc CREASE_UNIFORM / CREASE_CHAIKIN
//   triangles catmark|smooth               Sdc TRI_SUB_CATMARK / TRI_SUB_SMOOTH
//   vertices N      then N lines  x y z
//   faces F         then F lines  n v0 ... v(n-1)      (0-based vertex indices)
//   holes H         then H lines  face
//   creases C       then C lines  a b sharpness        (an edge by its two vertices)
//   corners K       then K lines  v sharpness
//   points P        then P lines  face u v
//
// Each point is in the face's own parameterisation (Bfr::Parameterization, as in
// opensubdiv/bfr/parameterization.h): a quad's (0,0) is its first vertex, u runs toward the
// second and v toward the last; a face of n != 4 sides is n quad sub-faces, sub-face k the
// half-unit square at tile (k mod d, k div d), d from the parameterisation.
//
// Output on stdout, one line per point, in order: "x y z" (%.17g), or "outside" for a point
// outside its face's domain (Bfr does not check: its results there are undefined), or
// "hole" for a face without a limit surface. Bad input (or any warning from Far while
// building the topology) prints one line "osd_eval: line L: problem" on stderr and exits 1.
//
// Options:
//   -l LEVEL   Bfr's approximation levels, smooth and sharp (default: the most, 10).
//   -tess RATE REPEATS
//              instead of points, Bfr's uniform tessellation (Bfr::Tessellation): every
//              face at RATE segments per edge, its points evaluated and its triangles
//              listed, REPEATS times from the control points (the topology is built
//              once, as a renderer would). Prints "ms T" (the median time of one
//              tessellation), "vertices V" and V lines "x y z", "triangles N" and N
//              lines "a b c" (0-based; a face's points are its own). The points section
//              is then "points 0".
//   -far LEVEL instead of Bfr, Far: the mesh refined uniformly LEVEL times and the limit
//              masks applied there (PrimvarRefiner::Limit), exact once every semi-sharp
//              feature has decayed, i.e. for LEVEL >= the largest finite sharpness, except
//              at darts (one infinitely sharp edge), which Sdc gives the smooth limit mask
//              (opensubdiv/sdc/scheme.h, ComputeVertexLimitMask). Only points that are
//              vertices of the first refinement have a limit point this way: a face's
//              corners, its edges' midpoints and its centre (a sub-face's (0,0), (1/2,0),
//              (0,1/2), (1/2,1/2)); any other point prints "not-a-vertex".

#include <opensubdiv/bfr/limits.h>
#include <opensubdiv/bfr/refinerSurfaceFactory.h>
#include <opensubdiv/bfr/surface.h>
#include <opensubdiv/bfr/tessellation.h>
#include <opensubdiv/far/error.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

using namespace OpenSubdiv;

namespace {

// Bfr approximates the limit surface of irregular (smooth) and sharp regions by refining
// them adaptively to these levels (defaults 2 and 6, opensubdiv/bfr/surfaceFactory.h).
// The sub-patches it builds are addressed by Far::PatchParam, whose 10-bit u and v
// indices "represent up through 10 levels of refinement" (opensubdiv/far/patchParam.h),
// and Far caps adaptive isolation at 10 (far/patchTableFactory.h): 10 is the most (at 11
// Bfr 3.5 crashes on points near a quad's (1,1) corner).
const int kMaxApproxLevel = 10;

int g_line = 0;

[[noreturn]] void fail(const std::string& msg) {
    std::fprintf(stderr, "osd_eval: line %d: %s\n", g_line, msg.c_str());
    std::exit(1);
}

// The next non-blank line, split into words.
std::vector<std::string> next_line() {
    std::string line;
    while (std::getline(std::cin, line)) {
        ++g_line;
        std::istringstream in(line);
        std::vector<std::string> words;
        std::string w;
        while (in >> w) words.push_back(w);
        if (!words.empty()) return words;
    }
    ++g_line;
    fail("unexpected end of input");
}

long parse_int(const std::string& s, long lo, long hi, const char* what) {
    errno = 0;
    char* end = nullptr;
    long v = std::strtol(s.c_str(), &end, 10);
    if (errno != 0 || end == s.c_str() || *end != '\0' || v < lo || v > hi) {
        fail(std::string(what) + " '" + s + "' is not an integer in " + std::to_string(lo) +
             ".." + std::to_string(hi));
    }
    return v;
}

double parse_double(const std::string& s, const char* what) {
    errno = 0;
    char* end = nullptr;
    double v = std::strtod(s.c_str(), &end);
    if (errno != 0 || end == s.c_str() || *end != '\0' || !std::isfinite(v)) {
        fail(std::string(what) + " '" + s + "' is not a finite number");
    }
    return v;
}

// Sharpness is a float in Far: parsed as one, so that the shortest decimal of an f32
// comes back as that f32.
float parse_sharpness(const std::string& s) {
    errno = 0;
    char* end = nullptr;
    float v = std::strtof(s.c_str(), &end);
    if (errno != 0 || end == s.c_str() || *end != '\0' || !std::isfinite(v) || v < 0.0f) {
        fail("sharpness '" + s + "' is not a finite number >= 0");
    }
    return v;
}

// "KEY VALUE" where VALUE is one of `choices`; returns its index.
int keyword(const char* key, std::vector<const char*> choices) {
    std::vector<std::string> w = next_line();
    if (w.size() != 2 || w[0] != key) fail(std::string("expected '") + key + " ...'");
    for (size_t i = 0; i < choices.size(); ++i) {
        if (w[1] == choices[i]) return (int)i;
    }
    fail(std::string(key) + " '" + w[1] + "' is not known");
}

// "KEY COUNT".
long count(const char* key) {
    std::vector<std::string> w = next_line();
    if (w.size() != 2 || w[0] != key) fail(std::string("expected '") + key + " COUNT'");
    return parse_int(w[1], 0, 100000000, "count");
}

std::vector<std::string> row(size_t words, const char* what) {
    std::vector<std::string> w = next_line();
    if (w.size() != words) {
        fail(std::string(what) + ": expected " + std::to_string(words) + " values, got " +
             std::to_string(w.size()));
    }
    return w;
}

std::string g_far_warning;

void on_far_warning(const char* msg) {
    if (g_far_warning.empty()) g_far_warning = msg;
}

void on_far_error(Far::ErrorType, const char* msg) {
    if (g_far_warning.empty()) g_far_warning = msg;
}

// Tiles per row of a face's quad sub-faces: vertex k sits at tile (k mod d, k div d), so d
// is the first vertex in the second row (Parameterization::GetVertexCoord).
int sub_face_tiles(const Bfr::Parameterization& p) {
    for (int k = 1; k < p.GetFaceSize(); ++k) {
        double uv[2];
        p.GetVertexCoord(k, uv);
        if (uv[1] == 1.0) return k;
    }
    return p.GetFaceSize();
}

// Whether (u, v) lies in the face's domain: the unit square for a quad, one sub-face's
// half-unit square otherwise.
bool in_domain(const Bfr::Parameterization& p, double u, double v) {
    if (!std::isfinite(u) || !std::isfinite(v)) return false;
    if (!p.HasSubFaces()) return u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0;
    double tu = std::floor(u), tv = std::floor(v);
    int d = sub_face_tiles(p);
    if (tu < 0.0 || tv < 0.0 || u - tu > 0.5 || v - tv > 0.5 || tu >= d) return false;
    return tv * d + tu < p.GetFaceSize();
}

struct Query {
    int face;
    double u, v;
};

const double* no_point(const char* why) {
    std::puts(why);
    return nullptr;
}

void print_point(const double p[3]) { std::printf("%.17g %.17g %.17g\n", p[0], p[1], p[2]); }

// Bfr: each face's limit surface, built on first use, evaluated at its (u, v).
void eval_bfr(const Far::TopologyRefiner& refiner, int level, const std::vector<double>& positions,
              const std::vector<Query>& queries) {
    Bfr::SurfaceFactory::Options options;
    options.SetApproxLevelSmooth(level);
    options.SetApproxLevelSharp(level);
    Bfr::RefinerSurfaceFactory<> factory(refiner, options);

    typedef Bfr::Surface<double> Surface;
    Surface::PointDescriptor xyz(3);
    struct FaceSurface {
        bool built = false;
        Surface surface;
        std::vector<double> patch_points;
    };
    std::vector<FaceSurface> surfaces(refiner.GetLevel(0).GetNumFaces());
    for (const Query& q : queries) {
        Bfr::Parameterization param(Sdc::SCHEME_CATMARK, refiner.GetLevel(0).GetFaceVertices(q.face).size());
        if (!in_domain(param, q.u, q.v)) {
            no_point("outside");
            continue;
        }
        FaceSurface& fs = surfaces[q.face];
        if (!fs.built) {
            fs.built = true;
            if (factory.InitVertexSurface<double>(q.face, &fs.surface)) {
                fs.patch_points.resize(3 * (size_t)fs.surface.GetNumPatchPoints());
                fs.surface.PreparePatchPoints(positions.data(), xyz, fs.patch_points.data(), xyz);
            }
        }
        if (!fs.surface.IsValid()) {
            no_point("hole");
            continue;
        }
        double uv[2] = {q.u, q.v};
        double p[3];
        fs.surface.Evaluate(uv, fs.patch_points.data(), xyz, p);
        print_point(p);
    }
}

// A point for Far's PrimvarRefiner (its Clear and AddWithWeight interface).
struct Point {
    double p[3];
    void Clear(void* = nullptr) { p[0] = p[1] = p[2] = 0.0; }
    void AddWithWeight(const Point& src, double w) {
        for (int i = 0; i < 3; ++i) p[i] += w * src.p[i];
    }
};

// The vertex of the first refinement at (u, v) of face f, or -1: a corner's vertex child,
// an edge's or the face's child vertex (Far::TopologyLevel's child queries).
int level1_vertex(const Far::TopologyLevel& base, int f, double u, double v) {
    Far::ConstIndexArray verts = base.GetFaceVertices(f);
    Far::ConstIndexArray edges = base.GetFaceEdges(f);  // edge k joins vertices k and k+1
    int n = verts.size();
    if (n == 4) {
        // (u, v) in units of the first refinement's grid.
        double a = 2.0 * u, b = 2.0 * v;
        if (a == 2.0 * std::floor(a / 2.0) && b == 2.0 * std::floor(b / 2.0)) {
            // A corner: (0,0), (1,0), (1,1), (0,1) are vertices 0, 1, 2, 3.
            int k = a == 0.0 ? (b == 0.0 ? 0 : 3) : (b == 0.0 ? 1 : 2);
            return base.GetVertexChildVertex(verts[k]);
        }
        if (a == 1.0 && b == 1.0) return base.GetFaceChildVertex(f);
        if (a == 1.0 && (b == 0.0 || b == 2.0)) return base.GetEdgeChildVertex(edges[b == 0.0 ? 0 : 2]);
        if (b == 1.0 && (a == 0.0 || a == 2.0)) return base.GetEdgeChildVertex(edges[a == 0.0 ? 3 : 1]);
        return -1;
    }
    // Sub-face k: (0,0) at vertex k, u toward vertex k+1 (edge k), v toward vertex k-1.
    Bfr::Parameterization param(Sdc::SCHEME_CATMARK, n);
    double local[2], uv[2] = {u, v};
    int k = param.ConvertCoordToSubFace(uv, local);
    double a = 2.0 * local[0], b = 2.0 * local[1];
    if (a == 0.0 && b == 0.0) return base.GetVertexChildVertex(verts[k]);
    if (a == 1.0 && b == 0.0) return base.GetEdgeChildVertex(edges[k]);
    if (a == 0.0 && b == 1.0) return base.GetEdgeChildVertex(edges[(k + n - 1) % n]);
    if (a == 1.0 && b == 1.0) return base.GetFaceChildVertex(f);
    return -1;
}

// Far: uniform refinement to `level`, then limit masks at the first refinement's vertices.
void eval_far(Far::TopologyRefiner& refiner, int level, const std::vector<double>& positions,
              const std::vector<Query>& queries) {
    Far::TopologyRefiner::UniformOptions uniform(level);
    uniform.fullTopologyInLastLevel = true;  // the limit masks read the last level's edges
    refiner.RefineUniform(uniform);
    Far::PrimvarRefinerReal<double> primvar(refiner);
    std::vector<Point> points(positions.size() / 3);
    for (size_t i = 0; i < points.size(); ++i) {
        for (int k = 0; k < 3; ++k) points[i].p[k] = positions[3 * i + k];
    }
    for (int l = 1; l <= level; ++l) {
        std::vector<Point> next(refiner.GetLevel(l).GetNumVertices());
        primvar.Interpolate(l, points, next);
        points.swap(next);
    }
    std::vector<Point> limit(points.size());
    primvar.Limit(points, limit);

    const Far::TopologyLevel& base = refiner.GetLevel(0);
    for (const Query& q : queries) {
        Bfr::Parameterization param(Sdc::SCHEME_CATMARK, base.GetFaceVertices(q.face).size());
        if (!in_domain(param, q.u, q.v)) {
            no_point("outside");
            continue;
        }
        if (base.IsFaceHole(q.face)) {
            no_point("hole");
            continue;
        }
        int v = level1_vertex(base, q.face, q.u, q.v);
        if (v < 0) {
            no_point("not-a-vertex");
            continue;
        }
        for (int l = 1; l < level; ++l) v = refiner.GetLevel(l).GetVertexChildVertex(v);
        print_point(limit[v].p);
    }
}

}  // namespace

// Bfr's uniform tessellation (-tess): the peer OpenSubdiv offers for a uniform grid.
void tess_bfr(const Far::TopologyRefiner& refiner, int level, const std::vector<double>& positions,
              int rate, int repeats) {
    Bfr::SurfaceFactory::Options options;
    options.SetApproxLevelSmooth(level);
    options.SetApproxLevelSharp(level);
    Bfr::RefinerSurfaceFactory<> factory(refiner, options);
    typedef Bfr::Surface<double> Surface;
    Surface::PointDescriptor xyz(3);
    Bfr::Tessellation::Options tess_options;
    tess_options.SetFacetSize(3);
    int faces = refiner.GetLevel(0).GetNumFaces();
    std::vector<double> points, patch_points, coords;
    std::vector<int> triangles, facets;
    std::vector<double> times;
    for (int r = 0; r < repeats; ++r) {
        points.clear();
        triangles.clear();
        auto start = std::chrono::steady_clock::now();
        Surface surface;
        for (int f = 0; f < faces; ++f) {
            if (!factory.InitVertexSurface<double>(f, &surface)) continue;  // a hole
            patch_points.resize(3 * (size_t)surface.GetNumPatchPoints());
            surface.PreparePatchPoints(positions.data(), xyz, patch_points.data(), xyz);
            Bfr::Tessellation tess(surface.GetParameterization(), rate, tess_options);
            int n = tess.GetNumCoords();
            coords.resize(2 * (size_t)n);
            tess.GetCoords(coords.data());
            int base = (int)(points.size() / 3);
            for (int k = 0; k < n; ++k) {
                double p[3];
                surface.Evaluate(&coords[2 * k], patch_points.data(), xyz, p);
                points.insert(points.end(), p, p + 3);
            }
            facets.resize(3 * (size_t)tess.GetNumFacets());
            tess.GetFacets(facets.data());
            for (int i : facets) triangles.push_back(base + i);
        }
        std::chrono::duration<double, std::milli> ms = std::chrono::steady_clock::now() - start;
        times.push_back(ms.count());
    }
    std::sort(times.begin(), times.end());
    std::printf("ms %.6f\n", times[times.size() / 2]);
    std::printf("vertices %zu\n", points.size() / 3);
    for (size_t i = 0; i < points.size(); i += 3) print_point(&points[i]);
    std::printf("triangles %zu\n", triangles.size() / 3);
    for (size_t i = 0; i < triangles.size(); i += 3) {
        std::printf("%d %d %d\n", triangles[i], triangles[i + 1], triangles[i + 2]);
    }
}

int main(int argc, char** argv) {
    int level = kMaxApproxLevel;
    int far_level = 0;
    int tess_rate = 0, tess_repeats = 0;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "-l") == 0 && i + 1 < argc) {
            level = (int)parse_int(argv[++i], 0, kMaxApproxLevel, "-l");
        } else if (std::strcmp(argv[i], "-tess") == 0 && i + 2 < argc) {
            tess_rate = (int)parse_int(argv[++i], 1, 4096, "-tess rate");
            tess_repeats = (int)parse_int(argv[++i], 1, 1000, "-tess repeats");
        } else if (std::strcmp(argv[i], "-far") == 0 && i + 1 < argc) {
            // UniformOptions keeps 4 bits of the level.
            far_level = (int)parse_int(argv[++i], 1, 15, "-far");
        } else {
            fail(std::string("unknown argument '") + argv[i] +
                 "' (usage: osd_eval [-l LEVEL | -far LEVEL | -tess RATE REPEATS] < input)");
        }
    }

    Sdc::Options sdc;
    sdc.SetVtxBoundaryInterpolation(keyword("boundary", {"edge-and-corner", "edge-only"}) == 0
                                        ? Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER
                                        : Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
    sdc.SetCreasingMethod(keyword("creasing", {"normal", "chaikin"}) == 0
                              ? Sdc::Options::CREASE_UNIFORM
                              : Sdc::Options::CREASE_CHAIKIN);
    sdc.SetTriangleSubdivision(keyword("triangles", {"catmark", "smooth"}) == 0
                                   ? Sdc::Options::TRI_SUB_CATMARK
                                   : Sdc::Options::TRI_SUB_SMOOTH);

    long nv = count("vertices");
    std::vector<double> positions;
    positions.reserve(3 * nv);
    for (long i = 0; i < nv; ++i) {
        std::vector<std::string> w = row(3, "vertex");
        for (const std::string& s : w) positions.push_back(parse_double(s, "coordinate"));
    }

    long nf = count("faces");
    std::vector<int> sizes;
    std::vector<int> indices;
    for (long f = 0; f < nf; ++f) {
        std::vector<std::string> w = next_line();
        long n = parse_int(w[0], 3, Bfr::Limits::MaxFaceSize(), "face size");
        if ((long)w.size() != n + 1) fail("face: expected " + std::to_string(n) + " vertex indices");
        sizes.push_back((int)n);
        for (long k = 1; k <= n; ++k) indices.push_back((int)parse_int(w[k], 0, nv - 1, "vertex index"));
    }

    long nh = count("holes");
    std::vector<int> holes;
    for (long i = 0; i < nh; ++i) holes.push_back((int)parse_int(row(1, "hole")[0], 0, nf - 1, "hole face"));

    long nc = count("creases");
    std::vector<int> crease_pairs;
    std::vector<float> crease_weights;
    for (long i = 0; i < nc; ++i) {
        std::vector<std::string> w = row(3, "crease");
        crease_pairs.push_back((int)parse_int(w[0], 0, nv - 1, "crease vertex"));
        crease_pairs.push_back((int)parse_int(w[1], 0, nv - 1, "crease vertex"));
        crease_weights.push_back(parse_sharpness(w[2]));
    }

    long nk = count("corners");
    std::vector<int> corner_vertices;
    std::vector<float> corner_weights;
    for (long i = 0; i < nk; ++i) {
        std::vector<std::string> w = row(2, "corner");
        corner_vertices.push_back((int)parse_int(w[0], 0, nv - 1, "corner vertex"));
        corner_weights.push_back(parse_sharpness(w[1]));
    }

    long np = count("points");
    std::vector<Query> queries;
    for (long i = 0; i < np; ++i) {
        std::vector<std::string> w = row(3, "point");
        queries.push_back({(int)parse_int(w[0], 0, nf - 1, "point face"), parse_double(w[1], "u"),
                           parse_double(w[2], "v")});
    }
    if (std::cin.peek() != EOF) {
        std::string rest;
        while (std::getline(std::cin, rest)) {
            ++g_line;
            if (rest.find_first_not_of(" \t\r") != std::string::npos) fail("unexpected input after the points");
        }
    }

    Far::TopologyDescriptor desc;
    desc.numVertices = (int)nv;
    desc.numFaces = (int)nf;
    desc.numVertsPerFace = sizes.data();
    desc.vertIndicesPerFace = indices.data();
    desc.numCreases = (int)nc;
    desc.creaseVertexIndexPairs = crease_pairs.data();
    desc.creaseWeights = crease_weights.data();
    desc.numCorners = (int)nk;
    desc.cornerVertexIndices = corner_vertices.data();
    desc.cornerWeights = corner_weights.data();
    desc.numHoles = (int)nh;
    desc.holeIndices = holes.data();
    desc.isLeftHanded = false;

    // Far reports a crease on an edge that does not exist, and invalid topology, as
    // warnings and carries on: here they are bad input.
    Far::SetWarningCallback(on_far_warning);
    Far::SetErrorCallback(on_far_error);
    typedef Far::TopologyRefinerFactory<Far::TopologyDescriptor> Factory;
    std::unique_ptr<Far::TopologyRefiner> refiner(
        Factory::Create(desc, Factory::Options(Sdc::SCHEME_CATMARK, sdc)));
    if (!g_far_warning.empty()) fail("Far: " + g_far_warning);
    if (!refiner) fail("Far could not build the topology");

    if (tess_rate > 0) {
        tess_bfr(*refiner, level, positions, tess_rate, tess_repeats);
    } else if (far_level > 0) {
        eval_far(*refiner, far_level, positions, queries);
    } else {
        eval_bfr(*refiner, level, positions, queries);
    }
    return std::fflush(stdout) == 0 ? 0 : 1;
}
