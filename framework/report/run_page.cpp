// The run's page: result.json, the pictures (inlined while they fit), the
// print's meshes decimated for viewing, the FEM's surface and fields, a
// caustic slab's receiver.
#include <algorithm>
#include <array>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "core/error.h"
#include "core/file_write.h"
#include "geometry/mesh_decimate.h"
#include "geometry/mesh_io.h"
#include "materials/material_library.h"
#include "report/fem_view.h"
#include "report/html_report.h"
#include "report/page.h"

namespace fs = std::filesystem;

namespace spec2fab {

namespace html_report {
namespace {

/// What a picture shows, from its file name (the translators' names).
std::string caption(const std::string& path) {
  static const std::vector<std::pair<std::string, std::string>> kCaptions = {
      {"goal_vs_achieved", "goal beside achieved"},
      {"texture_goal_vs_achieved", "the texture's goal beside achieved"},
      {"convergence", "error against evaluations"},
      {"optimizer_comparison", "the optimizers compared on this goal"},
      {"search", "branch and bound: what it evaluated and pruned"},
      {"render", "the print rendered from its slices' materials"},
      {"section_", "a cross-section through the middle of the tuned tree's materials"},
      {"goal", "the goal"},
      {"achieved", "what the tuned print gives"},
      {"simulated", "the simulated result"},
      {"traced", "the exported surface traced independently"},
      {"profile", "scattering profiles: goal and achieved"},
      {"deformation", "the deformed shape"},
  };
  const std::string stem = fs::path(path).stem().string();
  for (const auto& [key, text] : kCaptions)
    if (stem.find(key) != std::string::npos) return text;
  return "";
}

nlohmann::json images(const fs::path& folder, const nlohmann::json& result, size_t budget) {
  std::vector<std::string> paths;
  if (result.contains("files") && result["files"].contains("previews"))
    for (const auto& p : result["files"]["previews"]) paths.push_back(p.get<std::string>());
  std::set<std::string> listed(paths.begin(), paths.end());
  std::vector<std::string> others;
  for (const fs::path& sub : {fs::path("preview"), fs::path("")}) {
    if (!fs::is_directory(folder / sub)) continue;
    for (const auto& entry : fs::directory_iterator(folder / sub)) {
      const std::string relative = (sub / entry.path().filename()).generic_string();
      if (entry.is_regular_file() && entry.path().extension() == ".png" && !listed.count(relative)) others.push_back(relative);
    }
  }
  std::sort(others.begin(), others.end());
  paths.insert(paths.end(), others.begin(), others.end());
  // Goal beside achieved first, the print's render next, cross-sections last.
  const auto rank = [](const std::string& path) {
    const std::string stem = fs::path(path).stem().string();
    if (stem.find("goal_vs") != std::string::npos || stem.find("traced") != std::string::npos) return 0;
    if (stem == "render") return 1;
    if (stem.rfind("section_", 0) == 0) return 3;
    return 2;
  };
  std::stable_sort(paths.begin(), paths.end(), [&](const auto& a, const auto& b) { return rank(a) < rank(b); });
  nlohmann::json list = nlohmann::json::array();
  size_t used = 0;
  for (const std::string& path : paths) {
    if (!fs::is_regular_file(folder / path)) continue;
    const std::string bytes = read_bytes(folder / path);
    const auto [width, height] = png_size(bytes);
    nlohmann::json image = {{"name", path}, {"caption", caption(path)}, {"width", width}, {"height", height}};
    if (used + bytes.size() <= budget) {
      image["data"] = "data:image/png;base64," + base64(bytes);
      used += bytes.size();
    } else {
      image["caption"] = image["caption"].get<std::string>() + " (linked, not inlined: the page's picture budget is spent)";
    }
    list.push_back(std::move(image));
  }
  return list;
}

template <class T>
std::string packed(const std::vector<T>& values) {
  return base64(std::string_view(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T)));
}

nlohmann::json mesh_entry(const Mesh& shown, const std::string& name, size_t source_triangles) {
  std::vector<float> positions;
  positions.reserve(3 * shown.vertices.size());
  for (const Vec3& v : shown.vertices)
    positions.insert(positions.end(), {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())});
  std::vector<std::uint32_t> indices;
  indices.reserve(3 * shown.triangles.size());
  for (const Eigen::Vector3i& t : shown.triangles)
    for (int k = 0; k < 3; ++k) indices.push_back(static_cast<std::uint32_t>(t[k]));
  return {{"name", name}, {"positions", packed(positions)}, {"indices", packed(indices)},
          {"triangles", shown.triangles.size()}, {"source_triangles", source_triangles}};
}

/// The materials' display colours, when the library the run read is still there.
std::array<double, 3> colour_of(const std::string& material, const MaterialLibrary* library, size_t index) {
  static constexpr std::array<std::array<double, 3>, 8> kFallback = {{{0.85, 0.85, 0.85}, {0.0, 0.62, 0.85},
      {0.85, 0.2, 0.55}, {0.95, 0.8, 0.1}, {0.2, 0.2, 0.2}, {0.3, 0.7, 0.3}, {0.8, 0.45, 0.2}, {0.5, 0.4, 0.8}}};
  if (library) {
    try {
      const Rgb& c = library->get(material).display_srgb;
      return {c[0], c[1], c[2]};
    } catch (const std::exception&) {
    }
  }
  return kFallback[index % kFallback.size()];
}

nlohmann::json print_meshes(const fs::path& folder, const nlohmann::json& result, size_t triangle_budget,
                            std::vector<std::string>& notes) {
  std::vector<fs::path> stls;
  if (fs::is_directory(folder / "print"))
    for (const auto& entry : fs::directory_iterator(folder / "print"))
      if (entry.is_regular_file() && entry.path().extension() == ".stl") stls.push_back(entry.path());
  std::sort(stls.begin(), stls.end());
  std::optional<MaterialLibrary> library;
  try {
    const std::string file = result.at("inputs").at("materials").get<std::string>();
    if (fs::is_regular_file(file)) library = MaterialLibrary::load(file);
  } catch (const std::exception&) {
    notes.push_back("the material library the run read is not at hand: colours are stand-ins");
  }
  std::vector<Mesh> meshes;
  size_t total = 0;
  for (const fs::path& stl : stls) {
    try {
      meshes.push_back(load_mesh(stl, 1.0, default_limits(), MeshReaderProcess::this_one));
      total += meshes.back().triangles.size();
    } catch (const std::exception& e) {
      notes.push_back(fmt::format("{} is not shown: {}", fs::relative(stl, folder).generic_string(), e.what()));
      meshes.emplace_back();
    }
  }
  nlohmann::json list = nlohmann::json::array();
  for (size_t i = 0; i < stls.size(); ++i) {
    const Mesh& mesh = meshes[i];
    if (mesh.triangles.empty()) continue;
    // Each mesh's share of the budget follows its size, with a floor so a small part still reads.
    const size_t share = std::max<size_t>(2000, triangle_budget * mesh.triangles.size() / std::max<size_t>(1, total));
    const std::string name = stls[i].stem().string();
    nlohmann::json entry = mesh_entry(decimate_for_viewing(mesh, share), name, mesh.triangles.size());
    const auto c = colour_of(name, library ? &*library : nullptr, i);
    entry["color"] = c;
    entry["file"] = fs::relative(stls[i], folder).generic_string();
    list.push_back(std::move(entry));
  }
  // A caustic slab's smooth surface (surface.stl) and its voxel print overlap:
  // the surface is shown, the material regions one click away.
  const bool smooth_surface = std::any_of(list.begin(), list.end(), [](const auto& m) { return m["name"] == "surface"; });
  if (smooth_surface)
    for (auto& entry : list) {
      if (entry["name"] == "surface") {
        entry["color"] = {0.72, 0.84, 0.92};
      } else {
        entry["visible"] = false;
      }
    }
  return list;
}

nlohmann::json fem_entry(const fs::path& folder, std::vector<std::string>& notes) {
  const fs::path vtu = folder / "fem" / "fem.vtu";
  if (!fs::is_regular_file(vtu)) return nullptr;
  std::string why_not;
  nlohmann::json fem = fem_view(vtu, why_not);
  if (fem.is_null()) {
    notes.push_back("the FEM view is missing: " + why_not);
    return nullptr;
  }
  fem["probes"] = nlohmann::json::array();
  if (fs::is_regular_file(folder / "fem" / "probes.json")) fem["probes"] = read_json(folder / "fem" / "probes.json");
  return fem;
}

/// A caustic run's receiver: where the slab casts its image (a section with
/// distance_mm, receiver_mm and image_size, as the caustic translators
/// write) and the traced picture of the exported surface, cropped to the
/// cast image (the picture is the goal beside it).
nlohmann::json receiver_entry(const nlohmann::json& result, const nlohmann::json& images) {
  for (const auto& [name, section] : result.items()) {
    if (!section.is_object() || !section.contains("distance_mm") || !section.contains("receiver_mm") ||
        !section.contains("image_size"))
      continue;
    std::string picture;
    if (section.contains("surface_stl") && section["surface_stl"].contains("preview"))
      picture = section["surface_stl"]["preview"].get<std::string>();
    for (size_t i = 0; i < images.size(); ++i) {
      if (images[i]["name"] != picture || !images[i].contains("data")) continue;
      const int width = images[i]["width"], height = images[i]["height"];
      const int w = section["image_size"][0], h = section["image_size"][1];
      if (w > width || h > height) return nullptr;
      return {{"image", i}, {"crop", {width - w, 0, w, h}}, {"distance_mm", section["distance_mm"]},
              {"size_mm", section["receiver_mm"]}, {"caption", "the exported surface traced on the receiver"}};
    }
  }
  return nullptr;
}

}  // namespace
}  // namespace html_report

void write_run_report_html(const fs::path& folder, const std::string& purpose, const HtmlReportBudget& budget) {
  using namespace html_report;
  const nlohmann::json result = read_json(folder / "result.json");
  if (!result.is_object() || !result.contains("experiment") || !result.contains("translator"))
    throw InputError((folder / "result.json").string() + ": not a run's result.json (no experiment or translator)");
  nlohmann::json data = {{"kind", "run"}, {"purpose", purpose}, {"result", result}};
  if (fs::is_regular_file(folder / "convergence.csv")) data["convergence_csv"] = read_bytes(folder / "convergence.csv");
  if (fs::is_regular_file(folder / "experiment.json")) data["experiment"] = read_json(folder / "experiment.json");
  data["images"] = images(folder, result, budget.inline_image_bytes);
  std::vector<std::string> notes;
  nlohmann::json viewer = {{"meshes", print_meshes(folder, result, budget.triangles, notes)}};
  if (nlohmann::json fem = fem_entry(folder, notes); !fem.is_null()) {
    viewer["fem"] = std::move(fem);
    for (auto& mesh : viewer["meshes"]) mesh["visible"] = false;  // the print's regions stay one click away
  }
  if (nlohmann::json receiver = receiver_entry(result, data["images"]); !receiver.is_null())
    viewer["receiver"] = std::move(receiver);
  if (!viewer["meshes"].empty() || viewer.contains("fem")) data["viewer"] = std::move(viewer);
  data["notes"] = notes;
  data["files"] = file_list(folder);
  const nlohmann::json timing = fs::is_regular_file(folder / "timing.json") ? read_json(folder / "timing.json") : nlohmann::json();
  const std::string title = fmt::format("{} — spec2fab report", result["experiment"].get<std::string>());
  write_file(folder / "report.html", html_page(title, data, timing));
}

ReportFolderKind report_folder_kind(const fs::path& folder) {
  if (!fs::is_directory(folder)) throw InputError(folder.string() + ": not a folder");
  if (fs::is_regular_file(folder / "result.json")) return ReportFolderKind::run;
  if (fs::is_regular_file(folder / "report.json") && fs::is_directory(folder / "ioh")) return ReportFolderKind::bench;
  throw InputError(folder.string() + ": neither a run folder (result.json) nor a bench folder (report.json and ioh/)");
}

}  // namespace spec2fab
