// The OpenMesh side of the kernel comparison: the same meshes, sizes and loops as
// examples/kernel_peer.rs, on OpenMesh's PolyMesh_ArrayKernelT with double-precision
// points. Prints one line per measure, "name<TAB>value<TAB>unit", each the best of a
// few repetitions timed with std::chrono. Built and run by bench/openmesh/run.sh.

#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

#include <malloc.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <vector>

using Mesh = OpenMesh::PolyMesh_ArrayKernelT<OpenMesh::DefaultTraitsDouble>;
using P = Mesh::Point;
using OpenMesh::EdgeHandle;
using OpenMesh::FaceHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::VertexHandle;

namespace {

constexpr int REPS = 3;
constexpr int WALK_REPS = 10;  // the perimeter walks are short and noisy
constexpr uint32_t SMALL_N = 32, SMALL_M = 16;
constexpr uint32_t BIG_N = 1000, BIG_M = 500;
constexpr int SMALL_ROUNDS_TRI = 1000;
constexpr int SMALL_ROUNDS_QUAD = 2000;
constexpr double MAJOR = 3.0, MINOR = 1.0;
constexpr double TAU = 6.283185307179586;

template <size_t N>
struct Input {
  std::vector<P> positions;
  std::vector<std::array<uint32_t, N>> faces;
};

// The meshes of bench/mesh.rs, index for index.
std::vector<P> torus_positions(uint32_t n, uint32_t m) {
  std::vector<P> p;
  p.reserve(size_t(n) * m);
  for (uint32_t i = 0; i < n; ++i) {
    double u = TAU * double(i) / double(n);
    for (uint32_t j = 0; j < m; ++j) {
      double v = TAU * double(j) / double(m);
      double r = MAJOR + MINOR * std::cos(v);
      p.push_back(P(r * std::cos(u), r * std::sin(u), MINOR * std::sin(v)));
    }
  }
  return p;
}

std::array<uint32_t, 4> torus_quad(uint32_t n, uint32_t m, uint32_t i, uint32_t j) {
  auto at = [&](uint32_t i, uint32_t j) { return (i % n) * m + (j % m); };
  return {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
}

Input<4> torus_quads(uint32_t n, uint32_t m) {
  Input<4> in{torus_positions(n, m), {}};
  for (uint32_t i = 0; i < n; ++i)
    for (uint32_t j = 0; j < m; ++j) in.faces.push_back(torus_quad(n, m, i, j));
  return in;
}

Input<3> torus_triangles(uint32_t n, uint32_t m) {
  Input<3> in{torus_positions(n, m), {}};
  in.faces.reserve(size_t(2) * n * m);
  for (uint32_t i = 0; i < n; ++i)
    for (uint32_t j = 0; j < m; ++j) {
      auto q = torus_quad(n, m, i, j);
      in.faces.push_back({q[0], q[1], q[2]});
      in.faces.push_back({q[0], q[2], q[3]});
    }
  return in;
}

template <size_t N>
void build(Mesh& mesh, const Input<N>& in) {
  size_t nv = in.positions.size(), nf = in.faces.size();
  mesh.reserve(nv, nf * N / 2, nf);
  std::vector<VertexHandle> vh;
  vh.reserve(nv);
  for (const P& p : in.positions) vh.push_back(mesh.add_vertex(p));
  std::array<VertexHandle, N> c;
  for (const auto& f : in.faces) {
    for (size_t k = 0; k < N; ++k) c[k] = vh[f[k]];
    if (!mesh.add_face(c.data(), N).is_valid()) {
      std::fprintf(stderr, "add_face failed\n");
      std::exit(1);
    }
  }
}

void request_status(Mesh& mesh) {
  mesh.request_vertex_status();
  mesh.request_edge_status();
  mesh.request_face_status();
}

size_t live_faces(const Mesh& m) {
  size_t n = 0;
  for (auto f : m.faces()) (void)f, ++n;
  return n;
}
size_t live_edges(const Mesh& m) {
  size_t n = 0;
  for (auto e : m.edges()) (void)e, ++n;
  return n;
}
size_t live_vertices(const Mesh& m) {
  size_t n = 0;
  for (auto v : m.vertices()) (void)v, ++n;
  return n;
}

template <class F>
double best_ns(int reps, F&& f) {
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < reps; ++r) {
    auto t = std::chrono::steady_clock::now();
    f();
    auto d = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t);
    best = std::min(best, d.count());
  }
  return best;
}

// Without an argument every measure runs; with one, those whose name contains it.
const char* filter = nullptr;

bool wanted(std::initializer_list<const char*> names) {
  if (!filter) return true;
  for (const char* n : names)
    if (std::strstr(n, filter)) return true;
  return false;
}

void row(const char* name, double value, const char* unit) {
  std::printf("%s\t%.2f\t%s\n", name, value, unit);
  std::fflush(stdout);
}

volatile size_t sink;

// Split each edge at its midpoint (split_edge: a new vertex on the edge, no new faces)
// and collapse the new vertex back into the edge's first vertex, `rounds` times over all
// edges. The original edge survives each pair, so edge handles stay valid. Deleted items
// are collected between repetitions, outside the timing. Returns ns per pair.
double split_collapse(Mesh& mesh, int rounds, bool check) {
  std::vector<EdgeHandle> edges;
  for (auto e : mesh.edges()) edges.push_back(e);
  size_t nf = live_faces(mesh), ne = live_edges(mesh), nv = live_vertices(mesh);
  double best = std::numeric_limits<double>::infinity();
  size_t refused = 0;
  for (int rep = 0; rep < REPS; ++rep) {
    auto t = std::chrono::steady_clock::now();
    for (int r = 0; r < rounds; ++r) {
      for (EdgeHandle eh : edges) {
        HalfedgeHandle h0 = mesh.halfedge_handle(eh, 0);
        P mid = (mesh.point(mesh.from_vertex_handle(h0)) + mesh.point(mesh.to_vertex_handle(h0))) * 0.5;
        VertexHandle vh = mesh.add_vertex(mid);
        mesh.split_edge(eh, vh);
        // h0 now runs vh -> old to-vertex; the new edge runs old from-vertex -> vh.
        HalfedgeHandle back = mesh.opposite_halfedge_handle(mesh.prev_halfedge_handle(h0));
        if (check && !mesh.is_collapse_ok(back)) {
          ++refused;
          continue;
        }
        mesh.collapse(back);
      }
    }
    auto d = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t);
    best = std::min(best, d.count());
    mesh.garbage_collection();
  }
  if (refused || nf != live_faces(mesh) || ne != live_edges(mesh) || nv != live_vertices(mesh)) {
    std::fprintf(stderr, "split/collapse changed the mesh (%zu refused)\n", refused);
    std::exit(1);
  }
  return best / (double(rounds) * double(edges.size()));
}

// Cut each quad by its diagonal from its first vertex to its third (insert_edge) and
// remove the new edge again (remove_edge), `rounds` times over all faces. remove_edge
// keeps the face made by insert_edge, so the face list is updated with the survivor.
double insert_remove(Mesh& mesh, int rounds) {
  size_t nf = live_faces(mesh), ne = live_edges(mesh), nv = live_vertices(mesh);
  double best = std::numeric_limits<double>::infinity();
  size_t count = 0;
  for (int rep = 0; rep < REPS; ++rep) {
    std::vector<FaceHandle> faces;
    for (auto f : mesh.faces()) faces.push_back(f);
    count = faces.size();
    auto t = std::chrono::steady_clock::now();
    for (int r = 0; r < rounds; ++r) {
      for (FaceHandle& fh : faces) {
        HalfedgeHandle h0 = mesh.halfedge_handle(fh);
        HalfedgeHandle h2 = mesh.next_halfedge_handle(mesh.next_halfedge_handle(h0));
        HalfedgeHandle h3 = mesh.next_halfedge_handle(h2);
        // New edge from to(h3) = from(h0) to from(h2): the diagonal v0 - v2.
        HalfedgeHandle hn = mesh.insert_edge(h3, h2);
        fh = mesh.remove_edge(mesh.edge_handle(hn));
      }
    }
    auto d = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t);
    best = std::min(best, d.count());
    mesh.garbage_collection();
  }
  if (nf != live_faces(mesh) || ne != live_edges(mesh) || nv != live_vertices(mesh)) {
    std::fprintf(stderr, "insert/remove changed the mesh\n");
    std::exit(1);
  }
  for (auto f : mesh.faces())
    if (mesh.valence(f) != 4) {
      std::fprintf(stderr, "insert/remove left a face that is not a quad\n");
      std::exit(1);
    }
  return best / (double(rounds) * double(count));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1) filter = argv[1];
  auto big_tri = torus_triangles(BIG_N, BIG_M);

  if (wanted({"esplit_klev_small", "esplit_klev_small_checked"})) {
    Mesh mesh;
    build(mesh, torus_triangles(SMALL_N, SMALL_M));
    request_status(mesh);
    if (wanted({"esplit_klev_small"}))
      row("esplit_klev_small", split_collapse(mesh, SMALL_ROUNDS_TRI, false), "ns/pair");
    if (wanted({"esplit_klev_small_checked"}))
      row("esplit_klev_small_checked", split_collapse(mesh, SMALL_ROUNDS_TRI, true), "ns/pair");
  }
  if (wanted({"esplit_klev_1m", "esplit_klev_1m_checked"})) {
    Mesh mesh;
    build(mesh, big_tri);
    request_status(mesh);
    if (wanted({"esplit_klev_1m"}))
      row("esplit_klev_1m", split_collapse(mesh, 1, false), "ns/pair");
    if (wanted({"esplit_klev_1m_checked"}))
      row("esplit_klev_1m_checked", split_collapse(mesh, 1, true), "ns/pair");
  }
  if (wanted({"mkfe_klfe_small"})) {
    Mesh mesh;
    build(mesh, torus_quads(SMALL_N, SMALL_M));
    request_status(mesh);
    row("mkfe_klfe_small", insert_remove(mesh, SMALL_ROUNDS_QUAD), "ns/pair");
  }
  if (wanted({"mkfe_klfe_500k"})) {
    Mesh mesh;
    build(mesh, torus_quads(BIG_N, BIG_M));
    request_status(mesh);
    row("mkfe_klfe_500k", insert_remove(mesh, 1), "ns/pair");
  }
  if (wanted({"build_1m"})) {
    double ns = best_ns(REPS, [&] {
      Mesh mesh;
      build(mesh, big_tri);
      sink = mesh.n_faces();
    });
    row("build_1m", ns / 1e6, "ms");
  }
  if (!wanted({"bytes_per_edge_1m", "face_vertices_1m", "vertex_vertices_1m"})) return 0;

  // The mesh's weight: allocator bytes in use (arena and mmapped) after minus before.
  struct mallinfo2 m0 = mallinfo2();
  Mesh* mesh = new Mesh;
  build(*mesh, big_tri);
  struct mallinfo2 m1 = mallinfo2();
  size_t before = m0.uordblks + m0.hblkhd, after = m1.uordblks + m1.hblkhd;
  if (wanted({"bytes_per_edge_1m"}))
    row("bytes_per_edge_1m", double(after - before) / double(mesh->n_edges()), "B/edge");

  size_t uses = 0;
  if (wanted({"face_vertices_1m"})) {
    double ns = best_ns(WALK_REPS, [&] {
      size_t n = 0, acc = 0;
      for (auto f : mesh->faces())
        for (auto v : mesh->fv_range(f)) ++n, acc += v.idx();
      sink = acc;
      uses = n;
    });
    row("face_vertices_1m", ns / double(uses), "ns/use");
  }
  if (wanted({"vertex_vertices_1m"})) {
    double ns = best_ns(WALK_REPS, [&] {
      size_t n = 0, acc = 0;
      for (auto v : mesh->vertices())
        for (auto w : mesh->vv_range(v)) ++n, acc += w.idx();
      sink = acc;
      uses = n;
    });
    row("vertex_vertices_1m", ns / double(uses), "ns/use");
  }
  delete mesh;
  return 0;
}
