#include "reducer/node.h"
#include "reducer/nodes/nodes.h"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>

#include "core/error.h"
#include "core/limits.h"

#include "core/strings.h"

namespace spec2fab {

// The resource limits this part enforces (core/limits.h).
SPEC2FAB_LIMIT("tree_depth", 100, "levels of nesting in a reducer tree (the paper's trees are 5 deep; at most 1000)", 1000,
                "every walk over a tree recurses, and deeper trees would overflow the stack");
SPEC2FAB_LIMIT("column_cells", 1e6, "cells of one column node, each a subtree of nodes");

NodePtr build_node(const Properties& properties, const NodeContext& context) {
  if (const double max_depth = context.limits().get("tree_depth"); context.depth > max_depth) {
    properties.fail(fmt::format("the tree is nested more than {:g} levels deep here; a tree that deep is "
                                "refused (a generated tree gone wrong?) {}",
                                max_depth, context.limits().how_to_change("tree_depth")));
  }
  return NodeRegistry::instance().create(properties, "node", context);
}

ReducerNode::ReducerNode(const ReducerNode& other) : role_(other.role_) {
  children_.reserve(other.children_.size());
  for (const NodePtr& child : other.children_) children_.push_back(child->clone());
}

void ReducerNode::bind(const FrameDomain& incoming, BindContext& context) {
  for (NodePtr& child : children_) child->bind_domain(incoming, context);
}

LocalFrame frame_along_path(const ReducerNode& root, std::span<const size_t> path,
                            const QueryPoint& point, LocalFrame frame) {
  const ReducerNode* node = &root;
  for (size_t child : path) {
    frame = static_cast<const GeometryNode&>(*node).frame_in_child(child, point, frame);
    node = &node->child(child);
  }
  return frame;
}

namespace {

Parameter choice_over(const MaterialPalette& palette, const std::vector<std::string>& names, const std::string& value,
                      const std::string& where, bool free) {
  std::vector<double> ids;
  for (const std::string& name : names) ids.push_back(palette.id(name, where));
  return Parameter::choice(palette.id(value, where), std::move(ids), names, free);
}

}  // namespace

Parameter fixed_number(double value, const Parameter& declared) {
  if (!(value >= declared.lower() && value <= declared.upper()))
    throw std::logic_error(
        fmt::format("fixed_number: {} lies outside [{}, {}]", value, declared.lower(), declared.upper()));
  return Parameter::continuous(value, declared.lower(), declared.upper());
}

Parameter stratum_depth(double depth_mm, const std::string& where, const std::string& made_of) {
  const Parameter declared = StratumOptions{}.depth_mm;
  if (!(depth_mm > declared.lower() && depth_mm <= declared.upper())) {
    throw InputError(fmt::format("{}: {} make a shell {:g} mm deep; a stratum holds {}", where, made_of, depth_mm,
                                 depth_mm > declared.upper() ? fmt::format("at most {:g} mm", declared.upper())
                                                             : fmt::format("more than {:g} mm", declared.lower())));
  }
  return fixed_number(depth_mm, declared);
}

Parameter free_number(double value, double min, double max) {
  if (!(min <= value && value <= max))
    throw std::logic_error(fmt::format("free_number: {} lies outside [{}, {}]", value, min, max));
  return Parameter::continuous(value, min, max, true);
}

Parameter free_steps(double value, double min, double max, double step) {
  if (!(min <= value && value <= max && step > 0))
    throw std::logic_error(fmt::format("free_steps: {} in [{}, {}] by {}", value, min, max, step));
  return Parameter::discrete(value, min, max, step, true);
}

Parameter number_choice(double value, const std::vector<double>& choices) {
  if (std::find(choices.begin(), choices.end(), value) == choices.end())
    throw std::logic_error(fmt::format("number_choice: {} is not among the choices", value));
  std::vector<std::string> labels;
  for (double c : choices) labels.push_back(fmt::format("{:g}", c));  // as read_numeric_parameter labels them
  return Parameter::choice(value, choices, std::move(labels), true);
}

Parameter fixed_material(const MaterialPalette& palette, const std::string& name, const std::string& where) {
  return choice_over(palette, {name}, name, where, false);
}

Parameter material_choice(const MaterialPalette& palette, const std::string& value,
                          const std::vector<std::string>& names, const std::string& where) {
  if (std::find(names.begin(), names.end(), value) == names.end())
    throw std::logic_error("material_choice: '" + value + "' is not among the choices (" + join(names) + ")");
  return choice_over(palette, names, value, where, true);
}

Parameter read_material_parameter(const Properties& properties, const std::string& key,
                                  const NodeContext& context) {
  const MaterialPalette& palette = context.palette;
  auto choice_over = [&](const std::vector<std::string>& names, const std::string& value,
                         const std::string& where, bool free) {
    return spec2fab::choice_over(palette, names, value, where, free);
  };
  if (!properties.peek(key).is_object()) {
    const std::string name = properties.get<std::string>(key);
    return choice_over({name}, name, properties.where(key), false);
  }
  const Properties spec = properties.object(key);
  const std::string value = spec.get<std::string>("value");
  std::vector<std::string> names;
  if (spec.peek("choices").is_string()) {
    if (spec.get<std::string>("choices") != "all") spec.fail("choices", "expected an array of material names or \"all\"");
    names = palette.names();
  } else {
    names = spec.get<std::vector<std::string>>("choices");
  }
  if (names.empty()) spec.fail("choices", "no materials to choose from");
  if (std::find(names.begin(), names.end(), value) == names.end()) {
    spec.fail("value", "'" + value + "' is not among the choices (" + join(names) + ")");
  }
  return choice_over(names, value, spec.where("choices"), spec.get<bool>("free", true));
}

nlohmann::json material_parameter_to_json(const Parameter& parameter,
                                          const MaterialPalette& palette) {
  const std::string name = palette.name(static_cast<MaterialId>(parameter.value()));
  if (!parameter.is_free()) return name;
  return {{"value", name}, {"choices", parameter.labels()}};
}

void ChildNode::read(const Properties& properties, const char* name, const NodeContext& context) {
  if (required || properties.has(name)) node = build_node(properties.object(name), context.child());
}

void ChildNodes::read(const Properties& properties, const char* name, const NodeContext& context) {
  given = properties.has(name);
  if (!given) return;
  for (const Properties& child : properties.objects(name)) nodes.push_back(build_node(child, context.child()));
}

void MaterialOption::read(const Properties& properties, const char* name, const NodeContext& context) {
  if (!absent || properties.has(name)) parameter = read_material_parameter(properties, name, context);
}

bool RepeatedChildren::check(std::string* why) const {
  if ((child.node != nullptr) != children.given) return true;
  *why = "give either \"child\" (one node for every cell) or \"children\" (one per cell)";
  return false;
}

std::vector<NodePtr> RepeatedChildren::take(size_t count, const std::string& where, const Limits& limits) {
  // Each cell is a node of its own, with its share of every walk over the
  // tree: millions of them are a texture, which stack_grid holds in one node.
  // Measured in a run of a 1000 x 1000 column on a 50 mm sphere (Release, 2
  // threads): 1.07 kB and 2.2 us a cell.
  constexpr double kBytesPerCell = 1.1e3, kSecondsPerCell = 2.2e-6;
  if (const double max_cells = limits.get("column_cells"); static_cast<double>(count) > max_cells) {
    const auto cells = static_cast<double>(count);
    throw InputError(fmt::format("{}: {:.3g} cells of nodes (~{:.2g} GB, ~{} of a run), more than the {:.3g} one node "
                                 "may hold; a texture's columns belong in a stack_grid node {}",
                                 where, cells, cells * kBytesPerCell * 1e-9, format_seconds(cells * kSecondsPerCell),
                                 max_cells, limits.how_to_change("column_cells")));
  }
  std::vector<NodePtr> out;
  if (child.node) {
    out.reserve(count);
    for (size_t i = 1; i < count; ++i) out.push_back(child.node->clone());
    out.push_back(std::move(child.node));
    return out;
  }
  if (children.nodes.size() != count) {
    throw InputError(where + ": expected " + std::to_string(count) + " nodes, got " +
                     std::to_string(children.nodes.size()));
  }
  return std::move(children.nodes);
}

void repeated_children_to_json(const std::vector<NodePtr>& children,
                               const MaterialPalette& palette, nlohmann::json& out) {
  nlohmann::json list = nlohmann::json::array();
  for (const NodePtr& child : children) list.push_back(child->to_json(palette));
  const bool all_same =
      !list.empty() && std::all_of(list.begin(), list.end(), [&](const nlohmann::json& j) {
        return j == list.front();
      });
  if (all_same) {
    out["child"] = list.front();
  } else {
    out["children"] = std::move(list);
  }
}

void ReducerNode::read_parameters(
    const std::function<void(const std::string& name, const Parameter& parameter)>& read) const {
  // visit_parameters is non-const only so that tuners can set what they
  // visit; this visitor hands out const references and changes nothing.
  const_cast<ReducerNode*>(this)->visit_parameters([&](const std::string& name, Parameter& p) { read(name, p); });
}

std::optional<std::vector<MaterialId>> possible_materials(const ReducerNode& subtree) {
  std::vector<MaterialId> out;
  std::vector<const ReducerNode*> pending{&subtree};
  while (!pending.empty()) {
    const ReducerNode* node = pending.back();
    pending.pop_back();
    if (node->role() == ReducerNode::Role::material) {
      if (!static_cast<const MaterialNode*>(node)->possible_materials(out)) return std::nullopt;
    }
    for (size_t i = 0; i < node->child_count(); ++i) pending.push_back(&node->child(i));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

const MaterialNode& route_to_leaf(const ReducerNode& subtree, const QueryPoint& point, LocalFrame& frame) {
  const ReducerNode* node = &subtree;
  while (node->role() == ReducerNode::Role::geometry) {
    const GeometryNode::Route route = static_cast<const GeometryNode*>(node)->route(point, frame);
    node = &node->child(static_cast<size_t>(route.child));
    frame = route.frame;
  }
  return static_cast<const MaterialNode&>(*node);
}

MaterialId route_to_material(const ReducerNode& subtree, const QueryPoint& point, LocalFrame frame) {
  return route_to_leaf(subtree, point, frame).material(point, frame);
}

void sample_along_depth(const ReducerNode& subtree, double a, double b, double step_mm,
                        std::span<MaterialId> out) {
  const QueryPoint no_surface;  // the subtree is read in its own frame only
  for (size_t i = 0; i < out.size(); ++i) {
    out[i] = route_to_material(subtree, no_surface, {a, b, (static_cast<double>(i) + 0.5) * step_mm});
  }
}

}  // namespace spec2fab

SPEC2FAB_LIST_REGISTRY(spec2fab::NodeRegistry, 10, "node", "nodes")
