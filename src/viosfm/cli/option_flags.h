// The flags that set one option each, described once for every subcommand
// that has them. A flag names the option it sets by its key in a run's
// options.json (PipelineOptions); the option's own description (its
// struct's VisitFields, util/option_fields.h) gives the flag's default and,
// unless the flag says more, its help. A subcommand whose options are a part
// of a run's (`viosfm vio` binds the own VIO's, "own_vio.") binds the same
// flag to the same option inside that part, so `viosfm match --n1` and
// `viosfm run --n1` are one flag with one help.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "viosfm/util/option_fields.h"

namespace viosfm::cli {

enum class FlagValue {
  kText,     // the option's text: --n1 40
  kSeconds,  // seconds, of an option held in nanoseconds: --vio-max-gap 1.5
  kFixed,    // no value: sets the option to OptionFlag::fixed (--no-vio-prior: "false")
};

struct OptionFlag {
  std::string name;  // "--n1"
  // The run's option keys the flag sets: the first that lies in the
  // subcommand's options (e.g. --threads: a run's num_threads, the own
  // VIO's own_vio.window.num_threads for `viosfm vio`), or each that does
  // with every_key (--rolling-shutter-readout: one camera fact, two uses).
  std::vector<std::string> keys;
  FlagValue value = FlagValue::kText;
  std::string fixed;  // kFixed: the option's text the flag sets
  bool every_key = false;
  // The flag's help; empty: its option's help, capitalised. A kFixed or
  // kSeconds flag states its own.
  std::string help;
  // A former name, kept working for scripts and hidden from the help.
  std::string former_name;
};

// Every such flag, each once.
const std::vector<OptionFlag>& OptionFlags();
// The flag that sets the run's option `key`, or nullptr.
const OptionFlag* FlagOfKey(const std::string& key);

// The options a subcommand's flags set: its options struct as a part of a
// run's (keys below `prefix`), the struct's descriptions, and how a key of
// it is set from text.
struct OptionTarget {
  std::string prefix;                             // "" (a run's options) or e.g. "own_vio."
  std::vector<OptionDescription> descriptions;    // keys below the prefix
  std::map<std::string, std::string> type_names;  // by key: INT, FLOAT, TEXT, ...
  std::function<void(const std::string& key, const std::string& text)> set;
};

namespace internal {
template <class T>
std::string TypeName(const T&) {
  if constexpr (std::is_same_v<T, bool>) {
    return "BOOL";
  } else if constexpr (std::is_floating_point_v<T>) {
    return "FLOAT";
  } else if constexpr (std::is_integral_v<T>) {
    return "INT";
  } else if constexpr (std::is_same_v<T, std::filesystem::path>) {
    return "PATH";
  } else if constexpr (std::is_same_v<T, std::vector<int>>) {
    return "INT,...";
  } else {
    return "TEXT";
  }
}
}  // namespace internal

// `options` (which must outlive the subcommand's parse) as the part
// `prefix` of a run's options; `after_set` (if given) runs after each key
// is set.
template <class Options>
OptionTarget MakeOptionTarget(Options* options, std::string prefix,
                              std::function<void(const std::string& key)> after_set = {}) {
  OptionTarget target;
  target.prefix = std::move(prefix);
  target.descriptions = OptionDescriptions(*options);
  Options::VisitFields(*options, [&](const OptionField& field, const auto& value) {
    target.type_names[field.name] = internal::TypeName(value);
  });
  target.set = [options, after_set](const std::string& key, const std::string& text) {
    SetOptionFromText(*options, key, text);
    if (after_set) after_set(key);
  };
  return target;
}

// Adds the flags `names` (each one of OptionFlags()) to `command`, each
// setting its option(s) in `target`, in the order given (CLI11 applies them
// in the order they are added). A value the option does not take is an
// InputError naming the flag. A name that is not a flag of OptionFlags(),
// or whose option `target` lacks, is a bug (VIOSFM_CHECK).
void AddOptionFlags(CLI::App* command, const OptionTarget& target,
                    const std::vector<std::string>& names);

// The text of a value given in seconds as a whole number of nanoseconds;
// InputError naming `flag` for anything but a finite number.
std::string SecondsTextToNsText(const std::string& flag, const std::string& seconds);

}  // namespace viosfm::cli
