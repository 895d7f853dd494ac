#include "fem/mesh_cache.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <utility>

#include <malloc.h>

#include "core/error.h"
#include "core/run_cache.h"
#include "geometry/solid.h"

#include <spdlog/spdlog.h>

namespace spec2fab::fem {
namespace {

using Clock = std::chrono::steady_clock;

// FNV-1a over the surface's numbers.
std::string surface_fingerprint(const Mesh& mesh) {
  std::uint64_t hash = 1469598103934665603ull;
  auto add = [&](const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
  };
  for (const Vec3& v : mesh.vertices) add(v.data(), 3 * sizeof(double));
  for (const Eigen::Vector3i& t : mesh.triangles) add(t.data(), 3 * sizeof(int));
  return std::to_string(mesh.vertices.size()) + "/" + std::to_string(mesh.triangles.size()) + "/" +
         std::to_string(hash);
}

std::string key_of(const Solid& solid, const ReducerTree& tree, const TetgenOptions& options, bool follow) {
  std::ostringstream key;
  key.precision(17);
  key << surface_fingerprint(solid.mesh()) << "|" << options.max_volume_mm3 << "|" << options.radius_edge << "|";
  if (options.refine_box) {
    key << options.refine_box->min().transpose() << " " << options.refine_box->max().transpose() << " "
        << options.refine_max_volume_mm3;
  }
  key << "|" << follow << "|" << (follow ? tree.to_json().dump() : std::string());
  return key.str();
}

}  // namespace

std::shared_ptr<const ConformedMesh> conformed_mesh(const Solid& solid, const ReducerTree& tree,
                                                    const TetgenOptions& options, bool follow_interfaces,
                                                    RunCache* cache, bool* reused) {
  bool made_here = false;
  auto mesh = cached<const ConformedMesh>(cache, key_of(solid, tree, options, follow_interfaces), [&] {
    made_here = true;
    auto made = std::make_shared<ConformedMesh>();
    auto start = Clock::now();
    made->mesh = tetrahedralize(solid.mesh(), options);
    made->mesh_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    made->plain_tets = made->mesh.tets.size();
    start = Clock::now();
    if (follow_interfaces) {
      std::vector<int> labels;
      made->conform = conform_to_interfaces(made->mesh, tree, &labels);
      const bool several_pieces =
          std::any_of(labels.begin(), labels.end(), [&](int label) { return label != labels.front(); });
      if (several_pieces) {
        const Plc plc = labelled_mesh_plc(made->mesh, labels, solid.mesh().name, &made->plc);
        if (const char* dump = std::getenv("SPEC2FAB_FEM_POLY")) write_poly(plc, dump);
        const size_t first_pass_nodes = made->mesh.nodes.size();
        made->mesh = TetMesh{};  // the first pass's memory goes before the second pass takes its own
        TetgenOptions second = options;
        // The interfaces need more points than the plain solid where layers
        // are thinner than its tets; ten times as many means a runaway.
        second.max_steiner_points = static_cast<long>(10 * first_pass_nodes + 10000);
        try {
          made->mesh = tetrahedralize(plc, second);
          made->remeshed = true;
          if (made->mesh.nodes.size() >= plc.points.size() + static_cast<size_t>(second.max_steiner_points))
            spdlog::warn("fem: TetGen stopped adding points at {} with the interfaces as facets (a tiny feature "
                         "in them); the mesh there is coarser than asked",
                         second.max_steiner_points);
        } catch (const InputError& e) {
          // The solid alone meshed; its interfaces as facets did not: cut them in instead.
          spdlog::warn("fem: {}; the interfaces are cut into the solid's mesh instead", e.what());
          made->mesh = tetrahedralize(solid.mesh(), options);
        }
        made->cut_after = conform_to_interfaces(made->mesh, tree);
      }
    }
    made->conform_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    if (made->conform.interfaces_cut > 0)
      spdlog::info("fem: {} tets ({} for the solid alone, {} with the planar interfaces as facets), {} nodes; {} "
                   "interface(s) followed, {} cut in; {:.1f} s",
                   made->mesh.tets.size(), made->plain_tets, made->cut_after.tets_before, made->mesh.nodes.size(),
                   made->conform.interfaces_cut, made->plc.interfaces_left_out,
                   made->mesh_seconds + made->conform_seconds);
    // TetGen's pools are freed by now but glibc keeps their pages (~0.3 kB
    // per tet); hand them back so the solver's peak does not stand on them.
    malloc_trim(0);
    return std::shared_ptr<const ConformedMesh>(std::move(made));
  });
  if (reused) *reused = !made_here;
  return mesh;
}

}  // namespace spec2fab::fem
