// caustic_check: the command line of the independent caustic check
// (caustic_check.h). Prints one JSON object: SSIM, PSNR, RMSE, relative
// RMSE and the light off the receiver.
//
//   caustic_check --stl run/print/surface.stl --goal ring.png --distance 200
//                 [--receiver 60 60] [--image 240 240] [--rays 3840 3840] [--index 1.5]
//                 [--aperture disc] [--light 0 0 -1 | --point X Y Z] [--write traced.png]
//                 [--mirror-z] [--from-behind] [--exit-filter filter.txt]
//                 [--reflect] [--receiver-offset DX DY]
//
// --mirror-z traces the file upside down (light enters the face it has at
// the bottom); --from-behind images the receiver from its far side (columns
// towards -x); --exit-filter reads "nx ny" and nx × ny transmittances (row
// by row from the lowest y) of a filter on the face the light leaves by.
// --reflect makes the print a mirror (every face reflects; the receiver
// faces down from --distance above the print's lowest point);
// --receiver-offset moves the receiver's centre off the footprint's.
//
// The receiver is centred below the slab's footprint (the mesh's x–y
// bounds), at `distance` below its lowest point; light comes from above:
// collimated along --light, or from a point light at --point (the STL's
// coordinates) radiating evenly, the light through the footprint just
// above the slab being what the goal is scaled to.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>

#include "caustic_check.h"

namespace {

/// An exit filter from a text file: nx ny, then nx × ny transmittances row by
/// row from the lowest y, x fastest.
void read_exit_filter(const std::string& file, caustic_check::Options& o) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("cannot open " + file);
  if (!(in >> o.exit_cells[0] >> o.exit_cells[1]) || o.exit_cells[0] < 1 || o.exit_cells[1] < 1)
    throw std::runtime_error(file + ": expected the grid's nx ny first");
  o.exit_transmittance.resize(static_cast<size_t>(o.exit_cells[0]) * static_cast<size_t>(o.exit_cells[1]));
  for (double& t : o.exit_transmittance)
    if (!(in >> t)) throw std::runtime_error(file + ": fewer transmittances than nx × ny");
}

struct CommandLine {
  caustic_check::Options options;
  std::string write;
};

CommandLine parse(int argc, char** argv) {
  CommandLine line;
  caustic_check::Options& o = line.options;
  const auto need = [&](int i, int n) {
    if (i + n >= argc) throw std::runtime_error(std::string(argv[i]) + " needs " + std::to_string(n) + " value(s)");
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--stl") { need(i, 1); o.stl = argv[++i]; }
    else if (a == "--goal") { need(i, 1); o.goal = argv[++i]; }
    else if (a == "--write") { need(i, 1); line.write = argv[++i]; }
    else if (a == "--distance") { need(i, 1); o.distance_mm = std::stod(argv[++i]); }
    else if (a == "--index") { need(i, 1); o.index = std::stod(argv[++i]); }
    else if (a == "--receiver") { need(i, 2); o.receiver_mm = {std::stod(argv[i + 1]), std::stod(argv[i + 2])}; i += 2; }
    else if (a == "--image") { need(i, 2); o.image = {std::stoi(argv[i + 1]), std::stoi(argv[i + 2])}; i += 2; }
    else if (a == "--rays") { need(i, 2); o.rays = {std::stoi(argv[i + 1]), std::stoi(argv[i + 2])}; i += 2; }
    else if (a == "--light") { need(i, 3); o.light = {std::stod(argv[i + 1]), std::stod(argv[i + 2]), std::stod(argv[i + 3])}; i += 3; }
    else if (a == "--point") { need(i, 3); o.point = {std::stod(argv[i + 1]), std::stod(argv[i + 2]), std::stod(argv[i + 3])}; i += 3; }
    else if (a == "--aperture") { need(i, 1); o.disc = std::string(argv[++i]) == "disc"; }
    else if (a == "--mirror-z") { o.mirror_z = true; }
    else if (a == "--from-behind") { o.from_behind = true; }
    else if (a == "--exit-filter") { need(i, 1); read_exit_filter(argv[++i], o); }
    else if (a == "--reflect") { o.reflect = true; }
    else if (a == "--receiver-offset") { need(i, 2); o.receiver_offset_mm = {std::stod(argv[i + 1]), std::stod(argv[i + 2])}; i += 2; }
    else if (a == "--help" || a == "-h") {
      std::cout << "caustic_check --stl FILE --goal PNG --distance MM [--receiver W H] [--image W H] [--rays NX NY]\n"
                   "              [--index N] [--aperture rectangle|disc] [--light X Y Z | --point X Y Z] [--write PNG]\n"
                   "              [--mirror-z] [--from-behind] [--exit-filter FILE] [--reflect] [--receiver-offset DX DY]\n"
                   "Traces collimated light through the STL slab with its own tracer and prints the image's\n"
                   "SSIM, PSNR and RMSE against the goal as JSON (see tools/caustic_check/caustic_check.h).\n";
      std::exit(0);
    } else {
      throw std::runtime_error("unknown option " + a);
    }
  }
  if (o.stl.empty() || o.goal.empty() || !(o.distance_mm > 0)) throw std::runtime_error("--stl, --goal and --distance are required");
  return line;
}

}  // namespace

int main(int argc, char** argv) try {
  const CommandLine line = parse(argc, argv);
  const caustic_check::Result r = caustic_check::check(line.options);
  if (!line.write.empty()) {
    double peak;
    cv::minMaxLoc(r.goal, nullptr, &peak);
    caustic_check::write_traced(line.write, r.traced, peak);
  }
  std::printf("{\"ssim\": %.9g, \"psnr_db\": %s, \"rmse\": %.9g, \"relative_rmse\": %.9g, \"light_off_receiver\": %.9g, "
              "\"absorbed\": %.9g, \"rays\": %lld, \"triangles\": %zu}\n",
              r.ssim, std::isfinite(r.psnr_db) ? std::to_string(r.psnr_db).c_str() : "\"inf\"", r.rmse, r.relative_rmse,
              r.light_off_receiver, r.absorbed, r.rays, r.triangles);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "caustic_check: %s\n", e.what());
  return 2;
}
