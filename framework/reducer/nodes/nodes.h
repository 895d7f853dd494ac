#pragma once
/// Nodes composed in C++. Each node type's options are declared once, here:
/// the registry reads them from an experiment's JSON, and a translator that
/// builds its own tree fills them in C++ and calls the node's factory, so
/// that a misspelt option or type fails to compile instead of reaching the
/// user as an error in their file. The classes stay in their .cpp files;
/// what a caller needs of a node beyond ReducerNode is declared as a
/// capability of ReducerNode (height_surface()).
///
/// Options built in C++ must hold what their declaration says: a factory
/// refuses others with std::logic_error (require_valid), the caller's bug.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/options.h"
#include "reducer/node.h"
#include "reducer/nodes/height_cut.h"

namespace spec2fab {

// Parameters and materials as an experiment writes them, made in C++.

/// A number fixed at `value` ("offset_mm": 5) within the limits of the
/// option's declared default (`declared`).
Parameter fixed_number(double value, const Parameter& declared);
/// A stratum's depth, fixed at `depth_mm`. Where a translator adds a depth up
/// from its goal (layers, inks, a step of backing), this is its check: a depth
/// a stratum cannot hold ((0, 1000] mm) is an InputError, "<where>: <made_of>
/// make a shell D mm deep; a stratum holds at most 1000 mm", where
/// fixed_number would throw a logic_error (an internal error to the user).
Parameter stratum_depth(double depth_mm, const std::string& where, const std::string& made_of);
/// A number the tuners may move in [min, max] ({"value": v, "min": …, "max": …}).
Parameter free_number(double value, double min, double max);
/// A number the tuners may move in [min, max] in steps of `step` from min
/// ({"value": v, "min": …, "max": …, "step": …}).
Parameter free_steps(double value, double min, double max, double step);
/// A number the tuners choose among `choices` ({"value": v, "choices": […]}).
Parameter number_choice(double value, const std::vector<double>& choices);
/// A material fixed by name ("VeroClear"); throws InputError, placed at
/// `where`, for a name the palette lacks.
Parameter fixed_material(const MaterialPalette& palette, const std::string& name, const std::string& where);
/// A material the tuners choose among `names`, starting at `value`.
Parameter material_choice(const MaterialPalette& palette, const std::string& value,
                          const std::vector<std::string>& names, const std::string& where);

/// "layered": layers along the local depth axis; void is a material.
struct LayeredOptions {
  struct Layer {
    MaterialOption material;
    std::optional<Parameter> thickness_mm;
    std::string where;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.custom(o.material, "material", "the layer's material");
      d.parameter(o.thickness_mm, "thickness_mm", Range::closed(0, 1e4), "the layer's thickness",
                  Default{"unbounded (the last layer only)"});
    }
  };

  std::vector<Layer> layers;
  MaterialOption material{"-", std::nullopt}, fill{"the last layer's material", std::nullopt};
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.objects(o.layers, "layers",
              "outermost first; thickness_mm is a parameter (mm); the last layer may omit it and extend "
              "without end; give this or \"material\"");
    d.custom(o.material, "material", "shorthand for one unbounded layer");
    d.custom(o.fill, "fill", "material deeper than every layer");
  }
  bool check(std::string* why) const {
    if (material.parameter && !layers.empty()) *why = "give \"material\" or \"layers\", not both";
    else if (!material.parameter && layers.empty()) *why = "give \"layers\" (at least one) or \"material\"";
    else return true;
    return false;
  }
};
NodePtr make_layered(LayeredOptions options);
/// The commonest leaf: one unbounded layer of `material`.
NodePtr make_solid_material(Parameter material);

/// "plane" (Curved false) and "paraboloid": w = offset + s·d + ½ dᵀ K d.
template <bool Curved>
struct QuadricCutOptions {
  Parameter offset_mm = Parameter::continuous(0, -1e5, 1e5);
  Parameter slope_a = Parameter::continuous(0, -1e3, 1e3), slope_b = slope_a;
  Parameter curvature_aa = Parameter::continuous(0, -1e3, 1e3), curvature_ab = curvature_aa,
            curvature_bb = curvature_aa;
  std::array<double, 2> center{kUnset, kUnset};
  HeightCut::Options cut;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.parameter(o.offset_mm, "offset_mm", "height at the centre");
    d.parameter(o.slope_a, "slope_a", "dHeight/da at the centre");
    d.parameter(o.slope_b, "slope_b", "dHeight/db at the centre");
    if constexpr (Curved) {
      d.parameter(o.curvature_aa, "curvature_aa", "d²Height/da² (1/mm)");
      d.parameter(o.curvature_ab, "curvature_ab", "d²Height/da db (1/mm)");
      d.parameter(o.curvature_bb, "curvature_bb", "d²Height/db² (1/mm)");
    }
    d.number(o.center, "center", Range::any(), "[a0, b0], the pivot of the slopes",
             Default{"centre of the incoming domain"});
    HeightCut::Options::declare(d, o.cut);
  }
};
using PlaneOptions = QuadricCutOptions<false>;
using ParaboloidOptions = QuadricCutOptions<true>;
NodePtr make_plane(PlaneOptions options);
NodePtr make_paraboloid(ParaboloidOptions options);

/// "column": a grid of count[0] × count[1] columns, child i + count[0]·j.
struct ColumnOptions {
  std::array<int, 2> count{};
  std::array<double, 4> domain{kUnset, kUnset, kUnset, kUnset};
  RepeatedChildren cells;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.required(o.count, "count", Range::at_least(1), "columns along a and b; column (i, j) is cell i + na·j");
    d.number(o.domain, "domain", Range::any(), "[a_min, b_min, a_max, b_max], the area the grid covers",
             Default{"the incoming frame's extent"});
    RepeatedChildren::declare(d, o.cells);
  }
  bool check(std::string* why) const;
};
/// More cells than `limits`' "column_cells" (the run's) are refused.
NodePtr make_column(ColumnOptions options, const Limits& limits);

/// "bspline": a uniform bicubic B-spline height surface.
struct BSplineOptions {
  /// "heights_mm": one parameter for every control point, or one number each.
  struct ControlHeights {
    Parameter common = Parameter::continuous(0, -1e5, 1e5);
    std::vector<double> each;
    void read(const Properties& properties, const char* name, const NodeContext&);
    std::string type_text() const { return "parameter (mm), or array of na·nb numbers"; }
    std::string default_text() const { return "0"; }
  };

  std::array<int, 2> control{};
  ControlHeights heights_mm;
  std::array<double, 4> domain{kUnset, kUnset, kUnset, kUnset};
  HeightCut::Options cut;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.required(o.control, "control", Range::at_least(1), "control points along a and b");
    d.custom(o.heights_mm, "heights_mm", "control heights, row by row (a fastest)");
    d.number(o.domain, "domain", Range::any(), "[a_min, b_min, a_max, b_max], the area the control grid spans",
             Default{"the incoming frame's extent"});
    HeightCut::Options::declare(d, o.cut);
  }
  bool check(std::string* why) const;
};
NodePtr make_bspline(BSplineOptions options);

/// "voxel": uniform cells over the incoming frame, each its own child.
struct VoxelOptions {
  /// "size_mm": one edge for a cube, or three.
  struct CellSize {
    std::array<double, 3> edges{};
    void read(const Properties& properties, const char* name, const NodeContext&);
    std::string type_text() const { return "number or [sa, sb, sw] (mm)"; }
    std::string default_text() const { return "required"; }
  };

  CellSize size_mm;
  std::array<double, 3> origin{kUnset, kUnset, kUnset};
  RepeatedChildren cells;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.custom(o.size_mm, "size_mm", "cell size");
    d.number(o.origin, "origin", Range::any(), "[a, b, w], the corner of cell 0",
             Default{"the incoming domain's lower corner"});
    RepeatedChildren::declare(d, o.cells);
  }
  bool check(std::string* why) const { return cells.check(why); }
};
NodePtr make_voxel(VoxelOptions options);

/// "stratum": a shell of depth d under the surface, and the core below it.
struct StratumOptions {
  Parameter depth_mm = Parameter::continuous(1.0, 0, 1e3);
  ChildNode shell, core;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.parameter(o.depth_mm, "depth_mm", "shell thickness d");
    d.custom(o.shell, "shell", "child for depth < d");
    d.custom(o.core, "core", "child for depth >= d");
  }
};
NodePtr make_stratum(StratumOptions options);

}  // namespace spec2fab
