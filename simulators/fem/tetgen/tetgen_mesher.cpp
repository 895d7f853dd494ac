// The one translation unit that includes TetGen (AGPLv3), in a module of its
// own (spec2fab_tetgen, built with SPEC2FAB_WITH_TETGEN): linked, it registers
// itself as the mesher behind fem/tet_mesher.h.
#include "fem/tet_mesher.h"

#include <cstdio>
#include <sstream>
#include <string>

#include "core/build_options.h"
#include "core/error.h"

#include <tetgen.h>

namespace spec2fab::fem {

namespace {

std::string tetgen_failure(int code) {
  switch (code) {
    case 1: return "out of memory";
    case 2: return "internal error";
    case 3: return "the surface intersects itself";
    case 4: return "a very small input feature (or a self-intersection) was found";
    case 5: return "two very close input facets were found";
    case 10: return "an input error (e.g. an open or non-manifold surface)";
    default: return "error code " + std::to_string(code);
  }
}

TetMesh read_result(const tetgenio& out) {
  TetMesh mesh;
  mesh.nodes.reserve(static_cast<size_t>(out.numberofpoints));
  for (int i = 0; i < out.numberofpoints; ++i) {
    mesh.nodes.emplace_back(out.pointlist[3 * i], out.pointlist[3 * i + 1], out.pointlist[3 * i + 2]);
  }
  mesh.tets.reserve(static_cast<size_t>(out.numberoftetrahedra));
  for (int t = 0; t < out.numberoftetrahedra; ++t) {
    const int* c = &out.tetrahedronlist[t * out.numberofcorners];
    Tet tet{c[0], c[1], c[2], c[3]};
    mesh.tets.push_back(tet);
    if (mesh.volume(mesh.tets.size() - 1) < 0) std::swap(mesh.tets.back()[2], mesh.tets.back()[3]);
  }
  return mesh;
}

void run_tetgen(const std::string& switches, tetgenio& in, tetgenio& out, const std::string& name) {
  tetgenbehavior behaviour;
  std::vector<char> text(switches.begin(), switches.end());
  text.push_back('\0');
  if (!behaviour.parse_commandline(text.data())) {
    throw std::logic_error("TetGen rejected switches '" + switches + "'");
  }
  try {
    tetrahedralize(&behaviour, &in, &out);
  } catch (int code) {
    throw InputError(name + ": TetGen could not mesh the surface: " + tetgen_failure(code));
  }
}

TetMesh tetgen_tetrahedralize(const Plc& plc, const TetgenOptions& options) {
  const std::string& name = plc.name;
  tetgenio in;
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(plc.points.size());
  in.pointlist = new REAL[3 * plc.points.size()];
  for (size_t i = 0; i < plc.points.size(); ++i) {
    for (int d = 0; d < 3; ++d) in.pointlist[3 * i + static_cast<size_t>(d)] = plc.points[i][d];
  }
  in.numberoffacets = static_cast<int>(plc.facets.size());
  in.facetlist = new tetgenio::facet[plc.facets.size()];
  in.facetmarkerlist = new int[plc.facets.size()];
  for (size_t f = 0; f < plc.facets.size(); ++f) {
    tetgenio::facet& facet = in.facetlist[f];
    facet.numberofpolygons = 1;
    facet.polygonlist = new tetgenio::polygon[1];
    facet.numberofholes = 0;
    facet.holelist = nullptr;
    tetgenio::polygon& polygon = facet.polygonlist[0];
    polygon.numberofvertices = static_cast<int>(plc.facets[f].size());
    polygon.vertexlist = new int[plc.facets[f].size()];
    std::copy(plc.facets[f].begin(), plc.facets[f].end(), polygon.vertexlist);
    in.facetmarkerlist[f] = plc.markers.empty() ? 1 : plc.markers[f];
  }
  std::ostringstream switches;
  switches.precision(17);
  // p: a PLC; q: quality; a: volume bound; z: number from 0; Q: quiet.
  switches << "pzQq" << options.radius_edge << "a" << options.max_volume_mm3;
  if (options.max_steiner_points > 0) switches << "S" << options.max_steiner_points;
  tetgenio out;
  run_tetgen(switches.str(), in, out, name);
  if (!options.refine_box || !(options.refine_max_volume_mm3 > 0)) return read_result(out);

  // Second pass: a volume bound per tet, finer inside the box (-r refines the
  // given mesh, -a without a number reads the per-tet bounds).
  tetgenio again;
  again.firstnumber = 0;
  again.numberofpoints = out.numberofpoints;
  again.pointlist = new REAL[3 * static_cast<size_t>(out.numberofpoints)];
  std::copy(out.pointlist, out.pointlist + 3 * out.numberofpoints, again.pointlist);
  again.numberoftetrahedra = out.numberoftetrahedra;
  again.numberofcorners = 4;
  again.tetrahedronlist = new int[4 * static_cast<size_t>(out.numberoftetrahedra)];
  again.tetrahedronvolumelist = new REAL[static_cast<size_t>(out.numberoftetrahedra)];
  // The facets' triangles (the boundary and the interfaces) go along, so
  // that refining keeps them as faces.
  again.numberoftrifaces = out.numberoftrifaces;
  again.trifacelist = new int[3 * static_cast<size_t>(out.numberoftrifaces)];
  std::copy(out.trifacelist, out.trifacelist + 3 * out.numberoftrifaces, again.trifacelist);
  if (out.trifacemarkerlist) {
    again.trifacemarkerlist = new int[static_cast<size_t>(out.numberoftrifaces)];
    std::copy(out.trifacemarkerlist, out.trifacemarkerlist + out.numberoftrifaces, again.trifacemarkerlist);
  }
  for (int t = 0; t < out.numberoftetrahedra; ++t) {
    Vec3 centroid = Vec3::Zero();
    for (int k = 0; k < 4; ++k) {
      const int v = out.tetrahedronlist[t * out.numberofcorners + k];
      again.tetrahedronlist[4 * t + k] = v;
      centroid += 0.25 * Vec3(out.pointlist[3 * v], out.pointlist[3 * v + 1], out.pointlist[3 * v + 2]);
    }
    again.tetrahedronvolumelist[t] =
        options.refine_box->contains(centroid) ? options.refine_max_volume_mm3 : -1.0;
  }
  std::ostringstream refine;
  refine.precision(17);
  refine << "rzQq" << options.radius_edge << "a";
  if (options.max_steiner_points > 0) refine << "S" << options.max_steiner_points;
  tetgenio refined;
  run_tetgen(refine.str(), again, refined, name);
  return read_result(refined);
}

// Linked whole (every module is), so this runs before main().
[[maybe_unused]] const bool registered = register_tet_mesher(&tetgen_tetrahedralize);

}  // namespace
}  // namespace spec2fab::fem
