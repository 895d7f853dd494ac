#pragma once
// The FEM's solved mesh as the viewer shows it: the boundary surface of the
// active tets of a .vtu written by fem/vtu_writer (VTK XML, raw appended
// data), with each surface node's displacement and the von Mises stress
// averaged over its tets. Internal to report/.

#include <filesystem>

#include <nlohmann/json.hpp>

namespace spec2fab::html_report {

/// The viewer's "fem" entry for `vtu`, or null when the file is not one
/// this reader knows (the page then shows no FEM view and says why).
nlohmann::json fem_view(const std::filesystem::path& vtu, std::string& why_not);

}  // namespace spec2fab::html_report
