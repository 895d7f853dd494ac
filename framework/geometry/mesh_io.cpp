#include "geometry/mesh_io.h"
#include "core/file_write.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdlib>
#include <string_view>

#include <dlfcn.h>
#include <fcntl.h>
#include <spawn.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>
#include <fstream>
#include <sstream>
#include <memory>
#include <unordered_map>
#include <vector>

#include <assimp/DefaultIOSystem.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "core/error.h"
#include "core/limits.h"
#include "geometry/mesh_grammar_impl.h"

namespace spec2fab {

// The resource limits this part enforces (core/limits.h).
SPEC2FAB_LIMIT("mesh_read_seconds", 60, "seconds a mesh file's reader may take before the file is refused");

namespace {

// Hashes the exact bits of a position (with -0 folded onto +0) so that welding
// joins only identical coordinates.
struct PositionKey {
  std::uint64_t bits[3];
  explicit PositionKey(const Vec3& p) {
    for (int k = 0; k < 3; ++k) bits[k] = std::bit_cast<std::uint64_t>(p[k] + 0.0);
  }
  bool operator==(const PositionKey& o) const {
    return bits[0] == o.bits[0] && bits[1] == o.bits[1] && bits[2] == o.bits[2];
  }
};

struct PositionKeyHash {
  size_t operator()(const PositionKey& k) const {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (std::uint64_t b : k.bits) h = (h ^ b) * 0xff51afd7ed558ccdull, h ^= h >> 32;
    return static_cast<size_t>(h);
  }
};

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& verb, const std::string& reason) {
  mesh_file_error(file, verb, reason);
}

std::string one_line(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  return text.empty() ? std::string("unknown error") : text;
}

struct SceneWalker {
  const aiScene* scene;
  double scale;
  Mesh* mesh;
  std::unordered_map<PositionKey, int, PositionKeyHash> index_of;
  bool all_have_uv = true;

  int weld(const Vec3& p) {
    auto [it, inserted] =
        index_of.try_emplace(PositionKey(p), static_cast<int>(mesh->vertices.size()));
    if (inserted) mesh->vertices.push_back(p);
    return it->second;
  }

  void add(const aiMesh& m, const aiMatrix4x4& world) {
    const bool has_uv = m.HasTextureCoords(0);
    for (unsigned f = 0; f < m.mNumFaces; ++f) {
      const aiFace& face = m.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines left over by triangulation
      Eigen::Vector3i tri;
      for (int k = 0; k < 3; ++k) {
        const aiVector3D& v = m.mVertices[face.mIndices[k]];
        Vec3 p;
        for (int r = 0; r < 3; ++r)
          p[r] = (double(world[r][0]) * v.x + double(world[r][1]) * v.y +
                  double(world[r][2]) * v.z + double(world[r][3])) *
                 scale;
        tri[k] = weld(p);
        if (has_uv) {
          const aiVector3D& uv = m.mTextureCoords[0][face.mIndices[k]];
          mesh->corner_uv.emplace_back(uv.x, uv.y);
        }
      }
      if (!has_uv) all_have_uv = false;
      mesh->triangles.push_back(tri);
    }
  }

  void walk(const aiNode& node, const aiMatrix4x4& parent) {
    const aiMatrix4x4 world = parent * node.mTransformation;
    for (unsigned i = 0; i < node.mNumMeshes; ++i) add(*scene->mMeshes[node.mMeshes[i]], world);
    for (unsigned i = 0; i < node.mNumChildren; ++i) walk(*node.mChildren[i], world);
  }
};

void check_face_indices(const std::filesystem::path& file, const aiScene& scene) {
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes ? scene.mMeshes[m] : nullptr;
    if (mesh == nullptr) fail(file, "read", "corrupt file: an empty mesh record");
    if (mesh->mNumFaces > 0 && (mesh->mFaces == nullptr || mesh->mVertices == nullptr))
      fail(file, "read", "corrupt file: faces without vertices");
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices > 0 && face.mIndices == nullptr) fail(file, "read", "corrupt file: face " + std::to_string(f) + " has no corners");
      for (unsigned k = 0; k < face.mNumIndices; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices)
          fail(file, "read", "face " + std::to_string(f) + " refers to vertex " + std::to_string(face.mIndices[k]) +
                                 ", and there are " + std::to_string(mesh->mNumVertices));
      }
    }
  }
}

}  // namespace

namespace {

/// What Assimp may open while it reads a mesh: the mesh alone, one stream at
/// a time. An OBJ's material library (`mtllib`, or the .mtl of the OBJ's
/// name) is opened while the OBJ's own stream is open, so it never is: the
/// print's materials come from the library, and the file an OBJ names could
/// be anything beside it (in fuzz_mesh, the previous input; the OBJ itself,
/// by a path Assimp cleans up), handed to an MTL reader that Assimp 5.2.5
/// crashes on statements before `newmtl`.
class MeshFileOnly : public Assimp::DefaultIOSystem {
 public:
  explicit MeshFileOnly(std::string mesh) : mesh_(std::move(mesh)) {}
  bool Exists(const char* file) const override { return mesh_ == file && DefaultIOSystem::Exists(file); }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (mesh_ != file || open_ > 0) return nullptr;
    Assimp::IOStream* stream = DefaultIOSystem::Open(file, mode);
    if (stream != nullptr) ++open_;
    return stream;
  }
  void Close(Assimp::IOStream* stream) override {
    if (stream != nullptr) --open_;
    DefaultIOSystem::Close(stream);
  }

 private:
  std::string mesh_;
  int open_ = 0;
};

Mesh import_with_assimp(const std::filesystem::path& file, double scale_to_mm) {
  // No DefaultLogger is created, so Assimp stays silent (its NullLogger).
  Assimp::Importer importer;
  importer.SetIOHandler(new MeshFileOnly(file.string()));  // the importer owns it
  // Assimp's own text (its validation's internals, e.g. "aiMesh::mFaces[0]
  // .mNumIndices is 0") is not the user's: the formats with a grammar of
  // their own are checked before (check_ply_header, check_off,
  // check_binary_stl); what is left is said in our words.
  const std::string format = lowercase_extension(file);
  const auto unreadable = [&] {
    fail(file, "read",
         "not a valid " + (format.empty() ? std::string("mesh") : format.substr(1)) +
             " file (the reader found no mesh in it: malformed, truncated or another format)");
  };
  if (!importer.IsExtensionSupported(format))
    fail(file, "read", "unknown mesh format '" + format + "'; give .obj, .stl, .ply or .off");
  // Read without post-processing first: Assimp's steps (triangulation
  // included) abort the process on faces that point past the vertices,
  // which its readers pass through from a malformed file.
  const aiScene* scene = importer.ReadFile(file.string(), 0);
  if (scene == nullptr) unreadable();
  check_face_indices(file, *scene);
  scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_ValidateDataStructure);
  if (scene == nullptr) unreadable();
  if (scene->mRootNode == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    fail(file, "read", "no triangles");

  Mesh mesh;
  mesh.name = file.filename().string();
  SceneWalker walker{scene, scale_to_mm, &mesh, {}, true};
  walker.walk(*scene->mRootNode, aiMatrix4x4());
  if (mesh.triangles.empty()) fail(file, "read", "no triangles");
  if (!walker.all_have_uv) mesh.corner_uv.clear();
  return mesh;
}

template <class T>
void append_raw(std::string& out, const std::vector<T>& values) {
  const std::uint64_t count = values.size();
  out.append(reinterpret_cast<const char*>(&count), sizeof count);
  if (!values.empty()) out.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

template <class T>
bool take_raw(std::string_view& in, std::vector<T>& values) {
  std::uint64_t count = 0;
  if (in.size() < sizeof count) return false;
  std::memcpy(&count, in.data(), sizeof count);
  in.remove_prefix(sizeof count);
  if (count > in.size() / sizeof(T)) return false;
  values.resize(count);
  if (count > 0) std::memcpy(static_cast<void*>(values.data()), in.data(), count * sizeof(T));  // plain numbers (Eigen fixed-size)
  in.remove_prefix(count * sizeof(T));
  return true;
}

/// What the reader process sends back: 'M' and the mesh's arrays, or 'E'
/// and the refusal's text.
std::string read_mesh_answer(const std::filesystem::path& file, double scale_to_mm) {
  std::string answer;
  try {
    const Mesh mesh = import_with_assimp(file, scale_to_mm);
    answer.push_back('M');  // not = "M": g++ 12 warns falsely (-Wrestrict) on assigning a literal here
    append_raw(answer, mesh.vertices);
    append_raw(answer, mesh.triangles);
    append_raw(answer, mesh.corner_uv);
  } catch (const std::exception& e) {
    answer.assign(1, 'E');
    answer += e.what();
  }
  return answer;
}

// The reader runs with the default action of every deadly signal, so that
// the parent sees a crash as one (a fuzzer's or sanitizer's handler would
// report it as its own, or exit with a code of its own), and without
// stderr: what a crash prints (a sanitizer's report) is not the user's line.
void become_reader_process() {
  for (int signal : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL}) std::signal(signal, SIG_DFL);
  if (const int quiet = open("/dev/null", O_WRONLY); quiet >= 0) dup2(quiet, STDERR_FILENO);
}

[[noreturn]] void send_and_exit(int fd, const std::string& answer) {
  for (size_t sent = 0; sent < answer.size();) {
    const ssize_t n = write(fd, answer.data() + sent, answer.size() - sent);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) _exit(3);
    sent += static_cast<size_t>(n);
  }
  _exit(0);
}

constexpr const char* kReaderProgramName = "spec2fab-read-mesh";

bool is_program(const std::filesystem::path& file) {
  std::error_code error;
  return !file.empty() && std::filesystem::is_regular_file(file, error) && access(file.c_str(), X_OK) == 0;
}

/// The program spec2fab-read-mesh: named by SPEC2FAB_MESH_READER, else
/// beside the shared library that holds this function (the Python module),
/// beside the running program, in the build tree that made this code, or
/// where `cmake --install` put it. Only absolute places: a program found by
/// a relative name would be whatever the working folder holds. Empty when
/// none is.
std::filesystem::path reader_program() {
  static const std::filesystem::path found = [] {
    std::error_code error;
    if (const char* named = std::getenv("SPEC2FAB_MESH_READER"); named != nullptr && *named != '\0') {
      if (!is_program(named))
        throw InputError(std::string("SPEC2FAB_MESH_READER=") + named + ": not an executable file (unset it to use " +
                         kReaderProgramName + " beside spec2fab)");
      return std::filesystem::absolute(named, error);
    }
    std::vector<std::filesystem::path> places;
    const auto beside = [&](const std::filesystem::path& file) {
      if (file.is_absolute()) places.push_back(file.parent_path() / kReaderProgramName);
    };
    // dladdr names a shared object by the path it was loaded from, but the
    // main program by its argv[0]: relative names are skipped by `beside`.
    if (Dl_info info{}; dladdr(reinterpret_cast<void*>(&mesh_reader_main), &info) != 0 && info.dli_fname != nullptr)
      beside(info.dli_fname);
    beside(std::filesystem::read_symlink("/proc/self/exe", error));
#ifdef SPEC2FAB_MESH_READER_BUILT
    places.emplace_back(SPEC2FAB_MESH_READER_BUILT);
#endif
#ifdef SPEC2FAB_MESH_READER_INSTALLED
    places.emplace_back(SPEC2FAB_MESH_READER_INSTALLED);
#endif
    for (const auto& place : places)
      if (is_program(place)) return place;
    return std::filesystem::path();
  }();
  return found;
}

/// Starts spec2fab-read-mesh on the file, its stdout the pipe's write end.
/// A new program, not a fork of this one: a fork of a process with threads
/// (TBB's workers, the pools libraries start when loaded) may inherit a lock
/// another thread held — the allocator's, under a sanitizer — and hang in
/// its first allocation; posix_spawn starts the program afresh.
/// Returns posix_spawn's error number (0: started).
int spawn_reader(const std::filesystem::path& program, const std::filesystem::path& file, double scale_to_mm,
                 int write_end, pid_t& child) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, write_end, STDOUT_FILENO);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  // Not the signals this process blocks (SIGINT and SIGTERM, for its signal
  // thread). exec resets handled signals; ignored ones (nohup's SIGHUP) stay
  // ignored, as for any program this one starts.
  sigset_t none;
  sigemptyset(&none);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK);
  const std::string scale = fmt::format("{:.17g}", scale_to_mm);
  std::string program_text = program.string(), file_text = file.string();
  char* arguments[] = {program_text.data(), file_text.data(), const_cast<char*>(scale.c_str()), nullptr};
  const int error = posix_spawn(&child, program_text.c_str(), &actions, &attributes, arguments, environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  return error;
}

/// Runs Assimp in another process: its readers crash (SIGSEGV, aborted
/// assertions) and loop forever on some malformed files, which must cost a
/// clear refusal, not the run. That process is spec2fab-read-mesh where it
/// is found (reader_program), else a fork of this one. It sends back the
/// mesh, or the refusal's text; one that dies, or takes longer than
/// `seconds`, is named as such.
Mesh import_isolated(const std::filesystem::path& file, double scale_to_mm, const Limits& limits) {
  const double seconds = limits.get("mesh_read_seconds");
  const std::filesystem::path program = reader_program();
  int pipe_ends[2];
  if (pipe2(pipe_ends, O_CLOEXEC) != 0) return import_with_assimp(file, scale_to_mm);
  pid_t child = -1;
  if (!program.empty()) {
    if (const int error = spawn_reader(program, file, scale_to_mm, pipe_ends[1], child); error != 0) {
      close(pipe_ends[0]);
      close(pipe_ends[1]);
      fail(file, "read", "cannot start the mesh reader " + program.string() + ": " + std::strerror(error));
    }
  } else {
    child = fork();
    if (child < 0) {
      close(pipe_ends[0]);
      close(pipe_ends[1]);
      return import_with_assimp(file, scale_to_mm);
    }
    if (child == 0) {
      close(pipe_ends[0]);
      become_reader_process();
      send_and_exit(pipe_ends[1], read_mesh_answer(file, scale_to_mm));
    }
  }
  close(pipe_ends[1]);
  std::string answer;
  bool timed_out = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  for (char buffer[65536];;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    pollfd wait_for{pipe_ends[0], POLLIN, 0};
    const int ready = left.count() > 0 ? poll(&wait_for, 1, static_cast<int>(std::min<long long>(left.count(), 1000))) : 0;
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) {
      if (std::chrono::steady_clock::now() < deadline) continue;
      timed_out = true;
      kill(child, SIGKILL);
      break;
    }
    const ssize_t n = read(pipe_ends[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    answer.append(buffer, static_cast<size_t>(n));
  }
  close(pipe_ends[0]);
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out)
    fail(file, "read", fmt::format("the mesh reader (Assimp) did not finish in {:g} s; the file is malformed or far "
                                   "too large {}", seconds, limits.how_to_change("mesh_read_seconds")));
  // A reader program that exits with a status of its own is not at the
  // file's door: a missing library (127), a broken install.
  if (!program.empty() && WIFEXITED(status) && WEXITSTATUS(status) != 0)
    fail(file, "read", fmt::format("the mesh reader {} exited with status {} (a broken install? run it alone to see "
                                   "why)", program.string(), WEXITSTATUS(status)));
  if (WIFSIGNALED(status) || !WIFEXITED(status) || WEXITSTATUS(status) != 0 || answer.empty()) {
    const int signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
    fail(file, "read", std::string("the mesh reader (Assimp) crashed on it") +
                           (signal ? " (" + std::string(strsignal(signal)) + ")" : std::string()) + "; the file is malformed");
  }
  if (answer[0] == 'E') throw InputError(answer.substr(1));
  Mesh mesh;
  mesh.name = file.filename().string();
  std::string_view in(answer);
  in.remove_prefix(1);
  if (!take_raw(in, mesh.vertices) || !take_raw(in, mesh.triangles) || !take_raw(in, mesh.corner_uv) || !in.empty())
    fail(file, "read", "the mesh reader's answer was cut short");
  return mesh;
}

}  // namespace

Mesh load_mesh(const std::filesystem::path& file, double scale_to_mm, const Limits& limits, MeshReaderProcess process) {
  std::error_code error;
  if (!std::filesystem::exists(file, error)) fail(file, "read", "file not found");
  if (!std::filesystem::is_regular_file(file, error)) fail(file, "read", "not a regular file");
  if (!(scale_to_mm > 0)) fail(file, "read", "scale to mm must be positive");
  check_ply_header(file);
  check_off(file);
  check_binary_stl(file);
  check_obj(file);
  // Open MPI forbids fork() in its processes: under mpirun Assimp runs here.
  if (process == MeshReaderProcess::this_one || std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr)
    return import_with_assimp(file, scale_to_mm);
  return import_isolated(file, scale_to_mm, limits);
}

void mesh_reader_main(int argc, char** argv) {
  become_reader_process();
  if (argc != 3) send_and_exit(STDOUT_FILENO, "Espec2fab-read-mesh: give a mesh file and its scale to mm (run by spec2fab)");
  char* end = nullptr;
  const double scale_to_mm = std::strtod(argv[2], &end);
  if (end == argv[2] || *end != '\0' || !(scale_to_mm > 0))
    send_and_exit(STDOUT_FILENO, std::string("Espec2fab-read-mesh: not a positive scale: ") + argv[2]);
  send_and_exit(STDOUT_FILENO, read_mesh_answer(argv[1], scale_to_mm));
}

namespace {

// Splits vertices only where corner uvs differ (Assimp stores uvs per vertex).
std::unique_ptr<aiMesh> make_indexed_mesh(const Mesh& mesh) {
  std::vector<Vec3> positions;
  std::vector<Vec2> uvs;
  std::vector<int> corner_index(3 * mesh.triangles.size());
  if (mesh.has_uv()) {
    struct Key {
      int vertex;
      std::uint64_t u, v;
      bool operator==(const Key&) const = default;
    };
    struct KeyHash {
      size_t operator()(const Key& k) const {
        return std::hash<std::uint64_t>()(k.u * 31 + k.v) ^
               (size_t(k.vertex) * 0x9e3779b97f4a7c15ull);
      }
    };
    std::unordered_map<Key, int, KeyHash> index_of;
    for (size_t c = 0; c < corner_index.size(); ++c) {
      const int v = mesh.triangles[c / 3][c % 3];
      const Vec2& uv = mesh.corner_uv[c];
      const Key key{v, std::bit_cast<std::uint64_t>(uv.x()), std::bit_cast<std::uint64_t>(uv.y())};
      auto [it, inserted] = index_of.try_emplace(key, static_cast<int>(positions.size()));
      if (inserted) {
        positions.push_back(mesh.vertices[v]);
        uvs.push_back(uv);
      }
      corner_index[c] = it->second;
    }
  } else {
    positions = mesh.vertices;
    for (size_t c = 0; c < corner_index.size(); ++c) corner_index[c] = mesh.triangles[c / 3][c % 3];
  }

  auto out = std::make_unique<aiMesh>();
  out->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  out->mNumVertices = static_cast<unsigned>(positions.size());
  out->mVertices = new aiVector3D[positions.size()];
  for (size_t i = 0; i < positions.size(); ++i)
    out->mVertices[i] =
        aiVector3D(ai_real(positions[i].x()), ai_real(positions[i].y()), ai_real(positions[i].z()));
  if (!uvs.empty()) {
    out->mNumUVComponents[0] = 2;
    out->mTextureCoords[0] = new aiVector3D[uvs.size()];
    for (size_t i = 0; i < uvs.size(); ++i)
      out->mTextureCoords[0][i] = aiVector3D(ai_real(uvs[i].x()), ai_real(uvs[i].y()), 0);
  }
  out->mNumFaces = static_cast<unsigned>(mesh.triangles.size());
  out->mFaces = new aiFace[mesh.triangles.size()];
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    aiFace& face = out->mFaces[t];
    face.mNumIndices = 3;
    face.mIndices = new unsigned[3];
    for (int k = 0; k < 3; ++k) face.mIndices[k] = static_cast<unsigned>(corner_index[3 * t + k]);
  }
  return out;
}

// One vertex per corner with the face normal: STL stores a normal per facet,
// and Assimp's STL writer averages the vertex normals of each facet.
std::unique_ptr<aiMesh> make_facet_mesh(const Mesh& mesh) {
  auto out = std::make_unique<aiMesh>();
  const size_t n = 3 * mesh.triangles.size();
  out->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  out->mNumVertices = static_cast<unsigned>(n);
  out->mVertices = new aiVector3D[n];
  out->mNormals = new aiVector3D[n];
  out->mNumFaces = static_cast<unsigned>(mesh.triangles.size());
  out->mFaces = new aiFace[mesh.triangles.size()];
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Vec3 normal = (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                            .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]])
                            .normalized();
    aiFace& face = out->mFaces[t];
    face.mNumIndices = 3;
    face.mIndices = new unsigned[3];
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = mesh.vertices[tri[k]];
      out->mVertices[3 * t + k] = aiVector3D(ai_real(p.x()), ai_real(p.y()), ai_real(p.z()));
      out->mNormals[3 * t + k] =
          aiVector3D(ai_real(normal.x()), ai_real(normal.y()), ai_real(normal.z()));
      face.mIndices[k] = static_cast<unsigned>(3 * t + k);
    }
  }
  return out;
}

}  // namespace

void save_mesh(const Mesh& mesh, const std::filesystem::path& file) {
  const std::string extension = lowercase_extension(file);
  const char* format = extension == ".obj"   ? "objnomtl"
                       : extension == ".stl" ? "stlb"
                       : extension == ".ply" ? "ply"
                                             : nullptr;
  if (format == nullptr) fail(file, "write", "unknown extension (expected .obj, .stl or .ply)");
  if (mesh.triangles.empty()) fail(file, "write", "no triangles");

  aiScene scene;
  scene.mNumMeshes = 1;
  scene.mMeshes = new aiMesh*[1];
  scene.mMeshes[0] =
      (extension == ".stl" ? make_facet_mesh(mesh) : make_indexed_mesh(mesh)).release();
  scene.mNumMaterials = 1;
  scene.mMaterials = new aiMaterial*[1];
  scene.mMaterials[0] = new aiMaterial();
  scene.mRootNode = new aiNode();
  scene.mRootNode->mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned[1]{0};

  // Into memory, then written here: a refused write is the system's reason
  // (core/file_write.h), not a failure Assimp's stream would not report.
  Assimp::Exporter exporter;
  const aiExportDataBlob* blob = exporter.ExportToBlob(&scene, format);
  if (blob == nullptr || blob->next != nullptr) fail(file, "write", one_line(exporter.GetErrorString()));
  write_file(file, std::string_view(static_cast<const char*>(blob->data), blob->size));
}

}  // namespace spec2fab
