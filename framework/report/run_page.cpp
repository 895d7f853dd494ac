// The run's page: result.json, the pictures (inlined while they fit), the
// print's meshes decimated for viewing, the FEM's surface and fields, a
// caustic slab's receiver.
#include <algorithm>
#include <array>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "core/error.h"
#include "core/file_write.h"
#include "geometry/mesh_decimate.h"
#include "geometry/mesh_io.h"
#include "report/fem_view.h"
#include "report/html_report.h"
#include "report/page.h"

namespace fs = std::filesystem;

namespace spec2fab {

namespace html_report {
namespace {

/// A message with the folder's path taken out: a run writes its page in a
/// staging folder whose name changes from run to run.
std::string within(const fs::path& folder, std::string message) {
  const std::string prefix = folder.string() + "/";
  for (size_t at = message.find(prefix); at != std::string::npos; at = message.find(prefix, at))
    message.erase(at, prefix.size());
  return message;
}

/// What a picture shows, from its file name (the translators' names).
std::string caption(const std::string& path) {
  static const std::vector<std::pair<std::string, std::string>> kCaptions = {
      {"texture_goal_vs_achieved", "the texture's goal beside achieved"},  // before its suffix
      {"goal_vs_achieved", "goal beside achieved"},
      {"goal_vs_simulated", "goal beside simulated"},
      {"print_traced", "goal beside print/surface.stl traced by caustic_check, which shares no code with the simulator"},
      {"surface_stl_traced", "goal beside print/surface.stl traced by the simulator's own ray tracer"},
      {"convergence", "error against evaluations"},
      {"optimizer_comparison", "the optimizers compared on this goal"},
      {"search", "branch and bound: what it evaluated and pruned"},
      {"render", "the print rendered from its slices' materials"},
      {"section_", "a cross-section through the middle of the tuned tree's materials"},
      {"goal", "the goal"},
      {"achieved", "what the tuned print gives"},
      {"simulated", "the simulated result"},
      {"profile", "scattering profiles: goal and achieved"},
      {"deformation", "the deformed shape"},
      {"look", "the predicted colours in the shape's surface coordinates (the 3D view's texture)"},
  };
  const std::string stem = fs::path(path).stem().string();
  for (const auto& [key, text] : kCaptions)
    if (stem.find(key) != std::string::npos) return text;
  return "";
}

nlohmann::json images(const fs::path& folder, const nlohmann::json& result, size_t budget) {
  std::vector<std::string> paths;
  if (result.contains("files") && result["files"].contains("previews"))
    for (const auto& p : result["files"]["previews"])
      if (p.is_string()) paths.push_back(p.get<std::string>());
  std::set<std::string> listed(paths.begin(), paths.end());
  std::vector<std::string> others;
  for (const fs::path& sub : {fs::path("preview"), fs::path("")}) {
    if (!fs::is_directory(folder / sub)) continue;
    for (const auto& entry : fs::directory_iterator(folder / sub)) {
      const std::string relative = (sub / entry.path().filename()).generic_string();
      if (entry.is_regular_file() && entry.path().extension() == ".png" && !listed.count(relative))
        others.push_back(relative);
    }
  }
  std::sort(others.begin(), others.end());
  paths.insert(paths.end(), others.begin(), others.end());
  // The print traced independently (the headline's picture) first, goal
  // beside achieved next, then the print's render, cross-sections last.
  const auto rank = [](const std::string& path) {
    const std::string stem = fs::path(path).stem().string();
    if (stem == "print_traced") return 0;
    if (stem.find("goal_vs") != std::string::npos || stem.find("traced") != std::string::npos)
      return 1;
    if (stem == "render") return 2;
    if (stem.rfind("section_", 0) == 0) return 4;
    return 3;
  };
  std::stable_sort(paths.begin(), paths.end(),
                   [&](const auto& a, const auto& b) { return rank(a) < rank(b); });
  nlohmann::json list = nlohmann::json::array();
  size_t used = 0;
  for (const std::string& path : paths) {
    if (!fs::is_regular_file(folder / path)) continue;
    const std::string bytes = read_bytes(folder / path);
    const auto [width, height] = png_size(bytes);
    nlohmann::json image = {
        {"name", path}, {"caption", caption(path)}, {"width", width}, {"height", height}};
    if (used + bytes.size() <= budget) {
      image["data"] = "data:image/png;base64," + base64(bytes);
      used += bytes.size();
    } else {
      image["caption"] = image["caption"].get<std::string>() +
                         " (linked, not inlined: the page's picture budget is spent)";
    }
    list.push_back(std::move(image));
  }
  return list;
}

nlohmann::json mesh_entry(const Mesh& shown, const std::string& name, size_t source_triangles) {
  std::vector<float> positions;
  positions.reserve(3 * shown.vertices.size());
  for (const Vec3& v : shown.vertices)
    positions.insert(positions.end(), {static_cast<float>(v.x()), static_cast<float>(v.y()),
                                       static_cast<float>(v.z())});
  std::vector<std::uint32_t> indices;
  indices.reserve(3 * shown.triangles.size());
  for (const Eigen::Vector3i& t : shown.triangles)
    for (int k = 0; k < 3; ++k) indices.push_back(static_cast<std::uint32_t>(t[k]));
  return {{"name", name},
          {"positions", packed(positions)},
          {"indices", packed(indices)},
          {"triangles", shown.triangles.size()},
          {"source_triangles", source_triangles}};
}

/// The materials' display colours, from the slice stack's palette
/// (print/slices/manifest.json): the run folder's own record, so the page
/// does not depend on where `spec2fab report` runs or on the library now.
std::map<std::string, std::array<double, 3>> palette_colours(const fs::path& folder) {
  std::map<std::string, std::array<double, 3>> colours;
  const fs::path manifest = folder / "print" / "slices" / "manifest.json";
  if (!fs::is_regular_file(manifest)) return colours;
  const nlohmann::json palette = read_json(manifest).value("palette", nlohmann::json::array());
  for (const nlohmann::json& entry : palette) {
    if (!entry.is_object() || !entry.value("material", nlohmann::json()).is_string()) continue;
    const nlohmann::json srgb = entry.value("srgb", nlohmann::json());
    if (!srgb.is_array() || srgb.size() != 3 || !srgb[0].is_number() || !srgb[1].is_number() ||
        !srgb[2].is_number())
      continue;
    colours[entry["material"].get<std::string>()] = {
        srgb[0].get<double>() / 255, srgb[1].get<double>() / 255, srgb[2].get<double>() / 255};
  }
  return colours;
}

std::array<double, 3> colour_of(const std::string& material,
                                const std::map<std::string, std::array<double, 3>>& palette,
                                size_t index) {
  static constexpr std::array<std::array<double, 3>, 8> kFallback = {{{0.85, 0.85, 0.85},
                                                                      {0.0, 0.62, 0.85},
                                                                      {0.85, 0.2, 0.55},
                                                                      {0.95, 0.8, 0.1},
                                                                      {0.2, 0.2, 0.2},
                                                                      {0.3, 0.7, 0.3},
                                                                      {0.8, 0.45, 0.2},
                                                                      {0.5, 0.4, 0.8}}};
  const auto found = palette.find(material);
  return found != palette.end() ? found->second : kFallback[index % kFallback.size()];
}

nlohmann::json print_meshes(const fs::path& folder, size_t triangle_budget,
                            std::vector<std::string>& notes) {
  std::vector<fs::path> stls;
  if (fs::is_directory(folder / "print"))
    for (const auto& entry : fs::directory_iterator(folder / "print"))
      if (entry.is_regular_file() && entry.path().extension() == ".stl")
        stls.push_back(entry.path());
  std::sort(stls.begin(), stls.end());
  const auto palette = palette_colours(folder);
  if (!stls.empty() && palette.empty())
    notes.push_back(
        "print/slices/manifest.json holds no palette: the materials' colours are stand-ins");
  std::vector<Mesh> meshes;
  size_t total = 0;
  for (const fs::path& stl : stls) {
    try {
      meshes.push_back(load_mesh(stl, 1.0, default_limits(), MeshReaderProcess::this_one));
      total += meshes.back().triangles.size();
    } catch (const std::exception& e) {
      notes.push_back(fmt::format("{} is not shown ({})",
                                  fs::relative(stl, folder).generic_string(),
                                  within(folder, e.what())));
      meshes.emplace_back();
    }
  }
  nlohmann::json list = nlohmann::json::array();
  for (size_t i = 0; i < stls.size(); ++i) {
    const Mesh& mesh = meshes[i];
    if (mesh.triangles.empty()) continue;
    // Each mesh's share of the budget follows its size, with a floor so a small part still reads.
    const size_t share = std::max<size_t>(
        2000, triangle_budget * mesh.triangles.size() / std::max<size_t>(1, total));
    const std::string name = stls[i].stem().string();
    nlohmann::json entry =
        mesh_entry(decimate_for_viewing(mesh, share), name, mesh.triangles.size());
    const auto c = colour_of(name, palette, i);
    entry["color"] = c;
    entry["file"] = fs::relative(stls[i], folder).generic_string();
    list.push_back(std::move(entry));
  }
  // A caustic slab's smooth surface (surface.stl) and its voxel print overlap:
  // the surface is shown, the material regions one click away.
  const bool smooth_surface =
      std::any_of(list.begin(), list.end(), [](const auto& m) { return m["name"] == "surface"; });
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
  if (fs::is_regular_file(folder / "fem" / "probes.json"))
    fem["probes"] =
        read_json(folder / "fem" / "probes.json").value("probes", nlohmann::json::array());
  return fem;
}

/// A texture's predicted look on the shape (preview/look.obj and look.png,
/// the albedo translator's): corners welded where position and uv agree.
nlohmann::json look_entry(const fs::path& folder, const nlohmann::json& images,
                          std::vector<std::string>& notes) {
  constexpr size_t kLargest =
      200000;  // triangles (the albedo translator's limit too); beyond, preview/render.png
  if (!fs::is_regular_file(folder / "preview" / "look.obj")) return nullptr;
  size_t texture = images.size();
  for (size_t i = 0; i < images.size(); ++i)
    if (images[i]["name"] == "preview/look.png" && images[i].contains("data")) texture = i;
  if (texture == images.size()) return nullptr;
  Mesh mesh;
  try {
    mesh = load_mesh(folder / "preview" / "look.obj", 1.0, default_limits(),
                     MeshReaderProcess::this_one);
  } catch (const std::exception& e) {
    notes.push_back("the predicted look is not drawn on the shape: " + within(folder, e.what()));
    return nullptr;
  }
  if (!mesh.has_uv() || mesh.triangles.size() > kLargest) {
    notes.push_back(
        fmt::format("the predicted look is not drawn on the shape: {}",
                    mesh.has_uv() ? "over 200,000 triangles" : "no surface coordinates"));
    return nullptr;
  }
  std::map<std::pair<int, std::pair<float, float>>, std::uint32_t> welded;
  std::vector<float> positions, uv;
  std::vector<std::uint32_t> indices;
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.triangles[t][k];
      const Vec2& c = mesh.corner_uv[3 * t + static_cast<size_t>(k)];
      const auto key =
          std::make_pair(v, std::make_pair(static_cast<float>(c.x()), static_cast<float>(c.y())));
      auto [at, fresh] = welded.emplace(key, static_cast<std::uint32_t>(positions.size() / 3));
      if (fresh) {
        const Vec3& p = mesh.vertices[static_cast<size_t>(v)];
        positions.insert(positions.end(), {static_cast<float>(p.x()), static_cast<float>(p.y()),
                                           static_cast<float>(p.z())});
        uv.insert(uv.end(), {key.second.first, key.second.second});
      }
      indices.push_back(at->second);
    }
  return {{"name", "predicted look"},
          {"positions", packed(positions)},
          {"indices", packed(indices)},
          {"uv", packed(uv)},
          {"texture", texture},
          {"triangles", mesh.triangles.size()},
          {"source_triangles", mesh.triangles.size()},
          {"file", "preview/look.obj"}};
}

/// convergence.csv for the page: how many tuner runs it holds and the
/// traces of the first few (best error so far against evaluations, at most
/// kPoints each). A texture's thousands of column runs make a file of
/// hundreds of MB, which the page only counts.
nlohmann::json convergence(const fs::path& csv) {
  constexpr size_t kTraces = 10, kPoints = 400;
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // the header
  std::vector<std::pair<std::string, std::vector<std::array<double, 2>>>> traces;
  size_t runs = 0;
  std::string last_key;
  while (std::getline(in, line)) {
    // phase,sweep,tuner,iteration,evaluations,error,best_error
    std::array<std::string_view, 7> field;
    size_t at = 0;
    for (size_t k = 0; k < 7; ++k) {
      const size_t comma = k < 6 ? line.find(',', at) : line.size();
      if (comma == std::string::npos) break;
      field[k] = std::string_view(line).substr(at, comma - at);
      at = comma + 1;
    }
    const std::string key =
        std::string(field[0]) + " · sweep " + std::string(field[1]) + " · " + std::string(field[2]);
    if (key != last_key) {
      ++runs;
      last_key = key;
      if (traces.size() < kTraces) traces.push_back({key, {}});
    }
    if (runs <= kTraces && traces.back().first == key) {
      try {
        traces.back().second.push_back(
            {std::max(1.0, std::stod(std::string(field[4]))), std::stod(std::string(field[6]))});
      } catch (const std::exception&) {
      }
    }
  }
  nlohmann::json shown = nlohmann::json::array();
  for (auto& [key, points] : traces) {
    if (points.size() < 2) continue;
    std::vector<std::array<double, 2>> kept;
    const size_t step = (points.size() + kPoints - 1) / kPoints;
    for (size_t i = 0; i < points.size(); i += step) kept.push_back(points[i]);
    if (kept.back() != points.back()) kept.push_back(points.back());
    shown.push_back({{"label", key}, {"points", kept}});
  }
  return {{"runs", runs}, {"traces", shown}};
}

/// A caustic run's receiver: where the slab casts its image (a section with
/// distance_mm, receiver_mm and image_size, as the caustic translators
/// write) and the traced picture of the exported surface, cropped to the
/// cast image (the picture is the goal beside it).
nlohmann::json receiver_entry(const nlohmann::json& result, const nlohmann::json& images) {
  for (const auto& [name, section] : result.items()) {
    if (!section.is_object() || !section.contains("distance_mm") ||
        !section.contains("receiver_mm") || !section.contains("image_size"))
      continue;
    // The exported surface traced where the run traced it, else the estimator's image.
    const nlohmann::json& size = section["image_size"];
    if (!size.is_array() || size.size() != 2 || !size[0].is_number_integer() ||
        !size[1].is_number_integer() || !section["distance_mm"].is_number() ||
        !section["receiver_mm"].is_array())
      continue;
    std::string picture = "preview/goal_vs_simulated.png",
                caption = "the simulated image (the estimator's)";
    if (section.contains("surface_stl") && section["surface_stl"].is_object() &&
        section["surface_stl"].value("preview", nlohmann::json()).is_string()) {
      picture = section["surface_stl"]["preview"].get<std::string>();
      caption = "the exported surface traced on the receiver";
    }
    for (size_t i = 0; i < images.size(); ++i) {
      if (images[i]["name"] != picture || !images[i].contains("data")) continue;
      const int width = images[i]["width"], height = images[i]["height"];
      const int w = size[0], h = size[1];
      if (w > width || h > height) return nullptr;
      return {{"image", i},
              {"crop", {width - w, 0, w, h}},
              {"distance_mm", section["distance_mm"]},
              {"size_mm", section["receiver_mm"]},
              {"caption", caption}};
    }
  }
  return nullptr;
}

}  // namespace
}  // namespace html_report

namespace {

void write_run_page(const fs::path& folder, const std::string& purpose,
                    const std::map<std::string, std::string>& meanings,
                    const HtmlReportBudget& budget) {
  using namespace html_report;
  const nlohmann::json result = read_json(folder / "result.json");
  if (!result.is_object() || !result.contains("experiment") || !result.contains("translator"))
    throw InputError((folder / "result.json").string() +
                     ": not a run's result.json (no experiment or translator)");
  nlohmann::json data = {
      {"kind", "run"}, {"purpose", purpose}, {"result", result}, {"meanings", meanings}};
  if (fs::is_regular_file(folder / "convergence.csv"))
    data["convergence"] = convergence(folder / "convergence.csv");
  data["images"] = images(folder, result, budget.inline_image_bytes);
  std::vector<std::string> notes;
  nlohmann::json viewer = {{"meshes", print_meshes(folder, budget.triangles, notes)}};
  if (nlohmann::json fem = fem_entry(folder, notes); !fem.is_null()) {
    viewer["fem"] = std::move(fem);
    for (auto& mesh : viewer["meshes"])
      mesh["visible"] = false;  // the print's regions stay one click away
  }
  if (nlohmann::json look = look_entry(folder, data["images"], notes); !look.is_null()) {
    for (auto& mesh : viewer["meshes"])
      mesh["visible"] = false;  // the look first, the material regions a click away
    // Where the FEM's surface is drawn (deformation_texture), the look is a click away too: they
    // overlap.
    if (viewer.contains("fem")) look["visible"] = false;
    viewer["meshes"].insert(viewer["meshes"].begin(), std::move(look));
  }
  if (nlohmann::json receiver = receiver_entry(result, data["images"]); !receiver.is_null())
    viewer["receiver"] = std::move(receiver);
  if (!viewer["meshes"].empty() || viewer.contains("fem")) data["viewer"] = std::move(viewer);
  data["notes"] = notes;
  data["files"] = file_list(folder);
  const nlohmann::json timing = fs::is_regular_file(folder / "timing.json")
                                    ? read_json(folder / "timing.json")
                                    : nlohmann::json();
  const std::string title =
      fmt::format("{} — spec2fab report", result["experiment"].get<std::string>());
  write_file(folder / "report.html", html_page(title, data, timing));
}

}  // namespace

void write_run_report_html(const fs::path& folder, const std::string& purpose,
                           const std::map<std::string, std::string>& meanings,
                           const HtmlReportBudget& budget) {
  try {
    write_run_page(folder, purpose, meanings, budget);
  } catch (const nlohmann::json::exception& e) {
    // A result.json (or probes.json) edited or written by another version: the user's file, not a
    // bug.
    throw InputError((folder / "result.json").string() + ": a field of unexpected type (" +
                     e.what() + ")");
  }
}

ReportFolderKind report_folder_kind(const fs::path& folder) {
  if (!fs::is_directory(folder)) throw InputError(folder.string() + ": not a folder");
  if (fs::is_regular_file(folder / "result.json")) return ReportFolderKind::run;
  if (fs::is_regular_file(folder / "report.json") && fs::is_directory(folder / "ioh"))
    return ReportFolderKind::bench;
  throw InputError(
      folder.string() +
      ": neither a run folder (result.json) nor a bench folder (report.json and ioh/)");
}

}  // namespace spec2fab
