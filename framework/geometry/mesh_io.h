#pragma once
/// Mesh files in and out, through Assimp: OBJ (with texture coordinates),
/// STL (ASCII and binary), PLY and OFF.

#include <filesystem>

#include "core/limits.h"
#include "geometry/mesh.h"

namespace spec2fab {

/// Loads every triangle of every mesh in the file (node transforms applied),
/// scales it by `scale_to_mm` (1 for files in mm), welds vertices that share a
/// position exactly, and keeps per-corner uvs when the file has them.
/// Throws InputError ("file: cannot read mesh: reason") when the file is
/// missing, unreadable or holds no triangles. Does not check topology: see
/// mesh_check.h.
///
/// Each format's own grammar (OFF and PLY counts, a binary STL's size) is
/// checked before Assimp sees the file. Assimp's readers have crashed or
/// hung on malformed files these checks now refuse, so by default they still
/// run in a process of their own (mesh_reader_main): a reader that dies, or takes longer than
/// `limits`' "mesh_read_seconds" (the run's; 60 s by default), is
/// a refusal naming the file.
enum class MeshReaderProcess {
  automatic,  ///< a child process; this one under mpirun, whose processes must not fork
  this_one,   ///< this process (the fuzz harness: no fork per input, and a crash the checks let through is seen)
};
Mesh load_mesh(const std::filesystem::path& file, double scale_to_mm = 1.0, const Limits& limits = default_limits(),
               MeshReaderProcess process = MeshReaderProcess::automatic);

/// The program spec2fab-read-mesh (cli/read_mesh_main.cpp), which
/// load_mesh starts to read a file in a process of its own: arguments the
/// file and its scale to mm; writes the mesh, or the refusal, to stdout in
/// load_mesh's own encoding; never returns. load_mesh looks for the program
/// in SPEC2FAB_MESH_READER, beside the shared library that calls it, beside
/// the running program, in the build tree, where it was installed (absolute
/// places only); without it,
/// the reader runs in a fork of this process (which can hang where another
/// thread held a lock — the allocator's under a sanitizer — as it forked).
[[noreturn]] void mesh_reader_main(int argc, char** argv);

/// Writes a mesh (format from the extension: .obj, .stl, .ply) — used to make
/// datasets and test fixtures.
void save_mesh(const Mesh& mesh, const std::filesystem::path& file);

}  // namespace spec2fab
