// One description of every field of an Options struct, from which the
// options' text list (options.json), the listing of `viosfm run
// --list-options`, setting an option from text (`--set KEY=VALUE`) and the
// run's resume check (which options shape the stored data) are made.
//
// An Options struct describes its fields once, in a static member template:
//
//   struct FooOptions {
//     int num_things = 3;  // the long description stays here
//     BarOptions bar;
//     template <class Self, class Visitor>
//     static void VisitFields(Self& self, Visitor&& visit) {
//       visit({"num_things", "things per image", kShapesStoredData}, self.num_things);
//       VisitOptionGroup({"bar", "", kRunOnly}, self.bar, visit);
//     }
//   };
//
// `Self` is FooOptions or const FooOptions, so one description serves both
// reading and setting. A field's value is a bool, int, int64_t, uint64_t,
// double, std::string, std::filesystem::path, std::vector<int> or an enum
// for which OptionText(E) and ParseOptionText(text, E*) are declared next to
// it (found by argument-dependent lookup). A group's fields get its name and
// a dot in front; a run-only group makes all its fields run-only, an
// inactive one all inactive.
#pragma once

#include <filesystem>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "viosfm/util/errors.h"

namespace viosfm {

// Whether an option changes the features or matches a run stores (a re-run
// with another value cannot reuse them), or only how the run goes on from
// them (the mapper, thread counts, progress bars, paths whose content is
// hashed separately).
enum OptionEffect { kShapesStoredData, kRunOnly };

struct OptionField {
  std::string name;  // the key (part) in options.json
  std::string help;  // one line
  OptionEffect effect = kShapesStoredData;
  // false: the option does not apply to this run (e.g. the bag's topics
  // without a bag); it is left out of options.json and the fingerprint.
  bool active = true;
};

// The text of a value as options.json writes it: doubles with 10
// significant digits, bools "true"/"false", vectors comma-separated.
std::string OptionText(bool value);
std::string OptionText(int value);
std::string OptionText(int64_t value);
std::string OptionText(uint64_t value);
std::string OptionText(double value);
std::string OptionText(const std::string& value);
std::string OptionText(const std::filesystem::path& value);
std::string OptionText(const std::vector<int>& values);

// The value of a text; throws InputError saying what was expected.
void ParseOptionText(const std::string& text, bool* value);
void ParseOptionText(const std::string& text, int* value);
void ParseOptionText(const std::string& text, int64_t* value);
void ParseOptionText(const std::string& text, uint64_t* value);
void ParseOptionText(const std::string& text, double* value);
void ParseOptionText(const std::string& text, std::string* value);
void ParseOptionText(const std::string& text, std::filesystem::path* value);
void ParseOptionText(const std::string& text, std::vector<int>* values);

// Visits the fields of `options` (a struct with VisitFields) as fields of
// the group `group` (see the top of the file).
template <class Options, class Visitor>
void VisitOptionGroup(const OptionField& group, Options& options, Visitor& visit) {
  auto in_group = [&](OptionField field, auto& value) {
    field.name = group.name + "." + field.name;
    if (group.effect == kRunOnly) field.effect = kRunOnly;
    field.active = field.active && group.active;
    visit(field, value);
  };
  std::remove_const_t<Options>::VisitFields(options, in_group);
}

// Every active option as (key, value text), in the order VisitFields gives
// them; `prefix` goes in front of every key.
template <class Options>
std::vector<std::pair<std::string, std::string>> OptionsToKeyValues(
    const Options& options, const std::string& prefix = "") {
  std::vector<std::pair<std::string, std::string>> values;
  Options::VisitFields(options, [&](const OptionField& field, const auto& value) {
    if (field.active) values.emplace_back(prefix + field.name, OptionText(value));
  });
  return values;
}

// The active options that shape the stored data, as (key, value text).
template <class Options>
std::vector<std::pair<std::string, std::string>> StoredDataOptions(const Options& options) {
  std::vector<std::pair<std::string, std::string>> values;
  Options::VisitFields(options, [&](const OptionField& field, const auto& value) {
    if (field.active && field.effect == kShapesStoredData) {
      values.emplace_back(field.name, OptionText(value));
    }
  });
  return values;
}

struct OptionDescription {
  std::string key;
  std::string default_text;  // the value of a default-constructed struct
  std::string help;
  OptionEffect effect = kShapesStoredData;
};

// Every option (active or not) of `defaults`, for a listing.
template <class Options>
std::vector<OptionDescription> OptionDescriptions(const Options& defaults = Options{}) {
  std::vector<OptionDescription> descriptions;
  Options::VisitFields(defaults, [&](const OptionField& field, const auto& value) {
    descriptions.push_back({field.name, OptionText(value), field.help, field.effect});
  });
  return descriptions;
}

// Sets the option `key` (as in options.json) from `text`. Throws InputError
// naming the key and the text when the key is unknown or the text is not a
// value of the option.
template <class Options>
void SetOptionFromText(Options& options, const std::string& key, const std::string& text) {
  bool found = false;
  Options::VisitFields(options, [&](const OptionField& field, auto& value) {
    if (field.name != key) return;
    found = true;
    try {
      ParseOptionText(text, &value);
    } catch (const InputError& error) {
      throw InputError("option " + key + ": '" + text + "': " + error.what());
    }
  });
  if (!found) throw InputError("unknown option '" + key + "'");
}

}  // namespace viosfm
