// Render parameters: RenderParams, its declaration and the registries by name. Everything here is
// generated from core/params.def: the attributes of _core.RenderParams (a choice parameter reads
// and writes its name, resolved through its registry), _core.param_specs() (the declaration
// itself, from which sim.PipelineConfig, the stub and docs/config.md are built) and
// _core.choices() (every registry of names but the algorithms, which _core.algorithms() lists).
#include "bindings.h"

#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "core/params.h"
#include "frame/render.h"

namespace rast5d::bindings {

namespace {

template <class T>
const char* param_type() {
  if constexpr (IsChoice<T>::value || std::is_same_v<T, std::string>) return "str";
  else if constexpr (std::is_same_v<T, bool>) return "bool";
  else if constexpr (std::is_integral_v<T>) return "int";
  else if constexpr (std::is_floating_point_v<T>) return "float";
  else if constexpr (std::is_same_v<T, CoordRange>) return "range";
  else if constexpr (std::is_same_v<T, Precision>) return "precision";
}

// A stage's arithmetic as the user writes it: 'float64', 'float32' or {'fixed': {'int_bits', 'frac_bits'}}.
py::object precision_value(const Precision& p) {
  if (p.kind == PrecisionKind::kFloat64) return py::str("float64");
  if (p.kind == PrecisionKind::kFloat32) return py::str("float32");
  py::dict bits;
  bits["int_bits"] = p.int_bits, bits["frac_bits"] = p.frac_bits;
  py::dict d;
  d["fixed"] = bits;
  return d;
}

Precision precision_from(const py::object& v, const char* name) {
  const std::string shape = "expected 'float64', 'float32' or {fixed: {int_bits: int, frac_bits: int}}, got ";
  if (py::isinstance<py::str>(v)) {
    const std::string s = v.cast<std::string>();
    if (s == "float64") return Precision::float64();
    if (s == "float32") return Precision::float32();
  } else if (py::isinstance<py::dict>(v)) {
    const py::dict d = v.cast<py::dict>();
    if (d.size() == 1 && d.contains("fixed") && py::isinstance<py::dict>(d["fixed"])) {
      const py::dict b = d["fixed"].cast<py::dict>();
      if (b.size() == 2 && b.contains("int_bits") && b.contains("frac_bits") && py::isinstance<py::int_>(b["int_bits"]) &&
          py::isinstance<py::int_>(b["frac_bits"]) && !py::isinstance<py::bool_>(b["int_bits"]) &&
          !py::isinstance<py::bool_>(b["frac_bits"])) {
        const long long ib = b["int_bits"].cast<long long>(), fb = b["frac_bits"].cast<long long>();
        const Precision p = Precision::fixed(static_cast<int>(std::clamp(ib, -1LL, 1LL << 20)),
                                             static_cast<int>(std::clamp(fb, -1LL, 1LL << 20)));
        check_precision(name, p);
        return p;
      }
    }
  }
  throw std::invalid_argument(std::string(name) + ": " + shape + py::repr(v).cast<std::string>());
}

template <class T>
py::object param_value(const T& v) {
  if constexpr (IsChoice<T>::value) return py::str(std::string(choice_name(v)));
  else if constexpr (std::is_same_v<T, Precision>) return precision_value(v);
  else return py::cast(v);
}

template <class T>
void bind_param(py::class_<RenderParams>& c, const char* name, T RenderParams::*member) {
  if constexpr (IsChoice<T>::value) {
    c.def_property(
        name,
        [member](const RenderParams& p) { return std::string(choice_name(p.*member)); },
        [member, name](RenderParams& p, const std::string& v) { p.*member = choice_value<T>(v, name); });
  } else if constexpr (std::is_same_v<T, Precision>) {
    c.def_property(
        name, [member](const RenderParams& p) { return precision_value(p.*member); },
        [member, name](RenderParams& p, const py::object& v) { p.*member = precision_from(v, name); });
  } else {
    c.def_readwrite(name, member);
  }
}

template <std::size_t N>
py::list choice_list(const std::array<ChoiceInfo, N>& table) {
  py::list l;
  for (const auto& c : table) l.append(py::make_tuple(std::string(c.name), std::string(c.description)));
  return l;
}

template <class T>
void add_choices(py::dict& d) {
  if constexpr (IsChoice<T>::value)
    d[py::str(std::string(ChoiceTraits<T>::registry))] = choice_list(ChoiceTraits<T>::table);
}

// The registries of the choice parameters, in declaration order.
py::dict choices() {
  py::dict d;
#define RAST5D_PARAM(layer, group, key, type, def, unit, domain, doc) add_choices<type>(d);
#define RAST5D_PY_PARAM(layer, group, key, type, def, unit, domain, doc)
#define RAST5D_PARAM_GROUP(layer, name, keys, doc)
#include "core/params.def"
#undef RAST5D_PARAM
#undef RAST5D_PY_PARAM
#undef RAST5D_PARAM_GROUP
  return d;
}

// The names a row accepts: a choice enum's registry (whose name its "@registry" domain must
// spell), the traversal algorithms for "@algorithms", else None.
template <class T>
py::object choice_names(const char* key, const std::string& domain) {
  py::list l;
  if constexpr (IsChoice<T>::value) {
    const std::string reg = "@" + std::string(ChoiceTraits<T>::registry);
    if (domain.substr(0, domain.find(' ')) != reg)
      throw std::logic_error(std::string("params.def: ") + key + ": domain '" + domain + "' does not name its registry '" +
                             std::string(ChoiceTraits<T>::registry) + "'");
    for (const auto& c : ChoiceTraits<T>::table) l.append(std::string(c.name));
    return l;
  } else {
    if (domain.rfind("@algorithms", 0) != 0) return py::none();
    for (const auto& a : algorithms()) l.append(a.name);
    return l;
  }
}

// One row of param_specs().
py::dict param_spec(const char* stage, const char* kind, const char* layer, std::string group, const char* key,
                    const char* type, py::object def, const char* unit, const std::string& domain, const char* doc,
                    py::object choices) {
  py::dict d;
  if (!group.empty()) group.pop_back();  // "hiz_" -> "hiz"
  d["kind"] = kind;
  d["stage"] = stage;
  d["layer"] = layer;
  d["name"] = group.empty() ? std::string(key) : group + "." + key;
  const std::string engine = group.empty() ? std::string(key) : group + "_" + key;
  d["engine"] = std::string(kind) == "engine" ? py::object(py::str(engine)) : py::object(py::none());
  d["group"] = group.empty() ? py::object(py::none()) : py::object(py::str(group));
  d["type"] = type;
  d["default"] = def;
  d["unit"] = unit;
  d["domain"] = domain;
  d["doc"] = doc;
  d["choices"] = std::move(choices);
  return d;
}

py::list param_specs() {
  const RenderParams defaults;
  py::list l;
  const char* stage = "";
#define RAST5D_STAGE(name) stage = #name;
#define RAST5D_PARAM(layer, group, key, type, def, unit, domain, doc)                                             \
  l.append(param_spec(stage, "engine", #layer, #group, #key, param_type<type>(), param_value(defaults.group##key), \
                      unit, domain, doc, choice_names<type>(#group #key, domain)));
#define RAST5D_PY_PARAM(layer, group, key, type, def, unit, domain, doc)                                       \
  l.append(param_spec(stage, "python", #layer, #group, #key, param_type<type>(), param_value(type(def)), unit, \
                      domain, doc, choice_names<type>(#group #key, domain)));
#define RAST5D_PARAM_GROUP(layer, name, keys, doc)                                                    \
  {                                                                                                   \
    py::dict g;                                                                                       \
    g["kind"] = "group", g["stage"] = stage, g["layer"] = #layer, g["name"] = #name, g["keys"] = #keys; \
    g["doc"] = doc;                                                                                   \
    l.append(g);                                                                                      \
  }
#include "core/params.def"
#undef RAST5D_STAGE
#undef RAST5D_PARAM
#undef RAST5D_PY_PARAM
#undef RAST5D_PARAM_GROUP
  return l;
}

}  // namespace

void register_params(py::module_& m) {
  py::class_<RenderParams> c(m, "RenderParams");
  c.def(py::init<>());
#define RAST5D_PARAM(layer, group, key, type, def, unit, domain, doc) \
  bind_param(c, #group #key, &RenderParams::group##key);
#define RAST5D_PY_PARAM(layer, group, key, type, def, unit, domain, doc)
#define RAST5D_PARAM_GROUP(layer, name, keys, doc)
#include "core/params.def"
#undef RAST5D_PARAM
#undef RAST5D_PY_PARAM
#undef RAST5D_PARAM_GROUP
  m.def("param_specs", &param_specs,
        "The parameter declaration (params.def), one dict per row in order: kind ('engine', 'python' or "
        "'group'), stage (the pipeline stage of its section), layer, name (user path, 'hiz.tile_size'), "
        "engine (RenderParams field or None), group, "
        "type, default, unit, domain, doc, choices (names for a registry domain, else None); group rows: "
        "kind, stage, layer, name, keys ('all' or 'any'), doc.");
  m.def("choices", &choices, "Registries by name: {registry: [(name, description)]} in engine order.");
}

}  // namespace rast5d::bindings
