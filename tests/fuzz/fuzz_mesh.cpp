// Mesh files (STL, OBJ, PLY, OFF), as an experiment's geometry reads them:
// load_mesh, then the checks a Solid makes (closed, manifold, sound shells).
// Assimp runs in this process, as under mpirun: no fork per input, and a
// file the format checks let through to crash Assimp is a finding.
#include <cstring>

#include "fuzz_support.h"
#include "geometry/mesh_io.h"
#include "geometry/solid.h"

namespace {

// load_mesh chooses the reader by the extension: pick it from the content.
const char* extension_for(const std::uint8_t* data, std::size_t size) {
  const auto starts = [&](const char* magic) { return size >= std::strlen(magic) && std::memcmp(data, magic, std::strlen(magic)) == 0; };
  if (starts("ply")) return ".ply";
  if (starts("OFF")) return ".off";
  if (starts("solid") || (size >= 84 && !starts("v ") && !starts("#"))) return ".stl";
  return ".obj";
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spec2fab::fuzz::configure_harness();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = spec2fab::fuzz::input_file(data, size, std::string("input") + extension_for(data, size));
  return spec2fab::fuzz::accept_or_refuse([&] {
    spec2fab::Solid solid(spec2fab::load_mesh(file, 1.0, spec2fab::default_limits(), spec2fab::MeshReaderProcess::this_one),
                          spec2fab::UvSource::planar);
  });
}
