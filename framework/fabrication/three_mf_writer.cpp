#include "fabrication/three_mf_writer.h"
#include "core/file_write.h"

#include "fabrication/fabricate.h"
#include "fabrication/print_writer.h"

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cmath>
#include <stdexcept>

#include <Model/COM/NMR_DLLInterfaces.h>
#include <fmt/format.h>

namespace spec2fab {

namespace fs = std::filesystem;
using namespace NMR;

namespace {

// lib3mf's stream callbacks (ExportStream_WriteCallbackType and
// ExportStream_SeekCallbackType in its headers): 0 is success.
std::uint32_t write_to_file(std::uint8_t* data, std::uint32_t bytes, void* file) {
  static_cast<CheckedFile*>(file)->write(data, bytes);
  return 0;
}
std::uint32_t seek_in_file(std::uint64_t position, void* file) {
  auto* out = static_cast<CheckedFile*>(file);
  errno = 0;
  if (fseeko(out->get(), static_cast<off_t>(position), SEEK_SET) != 0) out->note_failure(errno);
  return 0;
}

// lib3mf 1.8's C API hands out reference-counted handles; this owns one.
class Handle {
 public:
  Handle() = default;
  ~Handle() {
    if (handle_) lib3mf_release(handle_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  PLib3MFBase** out() { return &handle_; }
  PLib3MFBase* get() const { return handle_; }

 private:
  PLib3MFBase* handle_ = nullptr;
};

void check(LIB3MFRESULT result, const char* what, const fs::path& file) {
  if (result != LIB3MF_OK) {
    throw std::runtime_error(file.string() + ": lib3mf: " + what + " failed (code " +
                             std::to_string(result) + ")");
  }
}

// lib3mf gives objects and build items random UUIDs; fixed ones keep the file
// byte-identical from run to run (same inputs, same output).
std::string fixed_uuid(unsigned kind, size_t index) {
  return fmt::format("5fab0000-0000-4000-8000-{:04x}{:08x}", kind, static_cast<unsigned>(index));
}

BYTE to_byte(double c) { return static_cast<BYTE>(std::lround(255 * std::clamp(c, 0.0, 1.0))); }

}  // namespace

void write_three_mf(const std::vector<Mesh>& meshes, const MaterialPalette& palette,
                    const fs::path& file) {
  Handle model, group;
  check(lib3mf_createmodel(model.out()), "create model", file);
  check(lib3mf_model_setunit(model.get(), MODELUNIT_MILLIMETER), "set unit", file);
  check(lib3mf_model_addbasematerialgroup(model.get(), group.out()), "add base materials", file);
  DWORD group_id = 0;
  check(lib3mf_resource_getresourceid(group.get(), &group_id), "get resource id", file);
  for (size_t id = 1; id < meshes.size(); ++id) {
    const Mesh& mesh = meshes[id];
    if (mesh.triangles.empty()) continue;
    const Material& material = palette.material(static_cast<MaterialId>(id));
    DWORD material_index = 0;
    const Rgb& c = material.display_srgb;
    check(lib3mf_basematerial_addmaterialutf8(group.get(), material.name.c_str(), to_byte(c[0]),
                                              to_byte(c[1]), to_byte(c[2]), &material_index),
          "add material", file);
    // addmaterial leaves alpha 0 (transparent); the materials are opaque.
    check(lib3mf_basematerial_setdisplaycolorrgba(group.get(), material_index, to_byte(c[0]),
                                                  to_byte(c[1]), to_byte(c[2]), 255),
          "set colour", file);

    std::vector<MODELMESHVERTEX> vertices(mesh.vertices.size());
    for (size_t v = 0; v < vertices.size(); ++v) {
      for (int k = 0; k < 3; ++k)
        vertices[v].m_fPosition[k] = static_cast<FLOAT>(mesh.vertices[v][k]);
    }
    std::vector<MODELMESHTRIANGLE> triangles(mesh.triangles.size());
    for (size_t t = 0; t < triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k)
        triangles[t].m_nIndices[k] = static_cast<DWORD>(mesh.triangles[t][k]);
    }
    Handle object, properties, item;
    check(lib3mf_model_addmeshobject(model.get(), object.out()), "add mesh object", file);
    check(lib3mf_object_setnameutf8(object.get(), material.name.c_str()), "set name", file);
    check(lib3mf_object_setuuidutf8(object.get(), fixed_uuid(1, id).c_str()), "set uuid", file);
    check(lib3mf_meshobject_setgeometry(object.get(), vertices.data(),
                                        static_cast<DWORD>(vertices.size()), triangles.data(),
                                        static_cast<DWORD>(triangles.size())),
          "set geometry", file);
    check(lib3mf_object_createdefaultpropertyhandler(object.get(), properties.out()),
          "property handler", file);
    check(lib3mf_defaultpropertyhandler_setbasematerial(properties.get(), group_id, material_index),
          "set material", file);
    check(lib3mf_model_addbuilditem(model.get(), object.get(), nullptr, item.out()),
          "add build item", file);
    check(lib3mf_builditem_setuuidutf8(item.get(), fixed_uuid(2, id).c_str()), "set uuid", file);
  }
  check(lib3mf_model_setbuilduuidutf8(model.get(), fixed_uuid(3, 0).c_str()), "set uuid", file);
  Handle writer;
  check(lib3mf_model_querywriter(model.get(), "3mf", writer.out()), "query writer", file);
  // Through callbacks into a CheckedFile that tells lib3mf every write
  // went well: a refused one is reported by close() as the system's reason
  // (core/file_write.h). lib3mf's own file stream, meeting a full disk,
  // threw from where nothing could catch it ("Could not deflate data",
  // then std::terminate).
  const fs::path partial = fs::path(file).concat(".partial");
  CheckedFile out(partial);
  check(lib3mf_writer_writetocallback(writer.get(), reinterpret_cast<void*>(&write_to_file),
                                      reinterpret_cast<void*>(&seek_in_file), &out),
        "write", partial);
  out.close();
  fs::rename(partial, file);
}

std::vector<ThreeMfObject> read_three_mf_objects(const fs::path& file) {
  Handle model, reader, iterator;
  check(lib3mf_createmodel(model.out()), "create model", file);
  check(lib3mf_model_queryreader(model.get(), "3mf", reader.out()), "query reader", file);
  check(lib3mf_reader_readfromfileutf8(reader.get(), file.c_str()), "read", file);
  check(lib3mf_model_getmeshobjects(model.get(), iterator.out()), "list mesh objects", file);
  std::vector<ThreeMfObject> objects;
  BOOL more = false;
  while (lib3mf_resourceiterator_movenext(iterator.get(), &more) == LIB3MF_OK && more) {
    Handle object;
    check(lib3mf_resourceiterator_getcurrent(iterator.get(), object.out()), "get object", file);
    ThreeMfObject o;
    ULONG needed = 0;
    check(lib3mf_object_getnameutf8(object.get(), nullptr, 0, &needed), "get name", file);
    std::string name(needed + 1, '\0');
    check(lib3mf_object_getnameutf8(object.get(), name.data(), needed + 1, &needed), "get name",
          file);
    o.name = name.c_str();
    DWORD count = 0;
    check(lib3mf_meshobject_getvertexcount(object.get(), &count), "vertex count", file);
    o.vertices = count;
    check(lib3mf_meshobject_gettrianglecount(object.get(), &count), "triangle count", file);
    o.triangles = count;
    BOOL manifold = false;
    check(lib3mf_meshobject_ismanifoldandoriented(object.get(), &manifold), "manifold check", file);
    o.manifold_and_oriented = manifold;
    objects.push_back(std::move(o));
  }
  return objects;
}

}  // namespace spec2fab

namespace spec2fab {
namespace {

class ThreeMfFile final : public PrintWriter {
 public:
  ThreeMfFile(const Properties& /*switch*/, const PrintWriterContext& context)
      : palette_(context.palette), folder_(context.folder) {}
  static TypeDoc doc() {
    return {"print/model.3mf: one named object per material in its display colour, assembled in one frame "
            "(lib3mf); the surfaces are the STLs'.",
            output_option_docs({"mesh_voxel_mm", "mesh_adaptivity"}),
            R"({"output": {"3mf": true}})"};
  }
  bool needs_surfaces() const override { return true; }
  void finish(const std::vector<Mesh>& surfaces, PrintFiles& report) override {
    write_three_mf(surfaces, palette_, folder_.path("print/model.3mf"));
    report.file("3mf", "print/model.3mf");
  }

 private:
  const MaterialPalette& palette_;
  RunFolder& folder_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::PrintWriterRegistry, spec2fab::ThreeMfFile, "3mf")
