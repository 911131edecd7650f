// Registries by name: a choice parameter is an enum E whose ChoiceTraits<E> specialisation (beside
// the enum, in core/params.h) names the registry and lists its entries in
// enum order. Adding a choice is one row of that table (and one enumerator); params.def, the
// bindings (_core.choices(), the RenderParams attribute read and written by name), the stub,
// sim.PipelineConfig, the pydantic schema and docs/config.md follow.
#pragma once

#include <array>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>

namespace rast5d {

// One entry of a registry by name.
struct ChoiceInfo {
  std::string_view name;
  std::string_view description;
};

// Specialised for each choice enum: `registry` (the name _core.choices() lists it under) and
// `table` (std::array<ChoiceInfo, N>, entry i naming enumerator i).
template <class E>
struct ChoiceTraits;

template <class T, class = void>
struct IsChoice : std::false_type {};
template <class T>
struct IsChoice<T, std::void_t<decltype(ChoiceTraits<T>::table)>> : std::true_type {};

// The index of `name` in a registry; std::invalid_argument naming the parameter and the choices.
template <std::size_t N>
int choice_index(const std::array<ChoiceInfo, N>& table, std::string_view name, std::string_view param) {
  std::string known;
  for (std::size_t i = 0; i < N; ++i) {
    if (table[i].name == name) return static_cast<int>(i);
    known.append(i ? ", " : "").append(table[i].name);
  }
  throw std::invalid_argument(std::string(param) + ": unknown '" + std::string(name) + "' (known: " + known + ")");
}

// The enumerator named `name` (std::invalid_argument naming `param` otherwise), and the reverse.
template <class E>
E choice_value(std::string_view name, std::string_view param) {
  return static_cast<E>(choice_index(ChoiceTraits<E>::table, name, param));
}
template <class E>
std::string_view choice_name(E value) {
  return ChoiceTraits<E>::table[static_cast<std::size_t>(value)].name;
}

}  // namespace rast5d
