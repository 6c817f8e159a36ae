// A stage's command-line options, each declared once. A declaration binds a
// flag to a field of the stage's options struct and, from that one line:
//  - adds it to CLI11, with its default (the field's value when declared)
//    shown in --help;
//  - records the value it ends with in the producer.options of every JSON
//    file the stage writes (Record);
//  - lists it in the stage's flag table in docs/stages/ (Markdown; the
//    stage prints it for `--help-markdown`, and a test keeps the docs current).
//
// Conventions, the same in every stage:
//  - a flag's record key is its name without "--", '-' read as '_';
//  - a named choice (an enum, or a string from a fixed set) goes through
//    Choice and is recorded by its name;
//  - an on/off setting is a Switch: `--x` turns it on, `--no-x` off, whatever
//    its default;
//  - input and output paths are Paths: they say where, not how, so they are
//    not recorded.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "common/json_io.h"

namespace docunfold {

class OptionTable {
 public:
  explicit OptionTable(CLI::App& app) : app_(app) {}
  OptionTable(const OptionTable&) = delete;
  OptionTable& operator=(const OptionTable&) = delete;

  CLI::App& app() { return app_; }

  // --name VALUE into *field (a number or a string).
  template <typename T>
  CLI::Option* Value(const std::string& name, T* field, const std::string& help) {
    CLI::Option* option = app_.add_option(Flag(name), *field, help)->capture_default_str();
    Add(name, option, [field] { return Json(*field); });
    return option;
  }

  // --name VALUE, VALUE within [lo, hi].
  template <typename T>
  CLI::Option* Value(const std::string& name, T* field, T lo, T hi, const std::string& help) {
    return Value(name, field, help)->check(CLI::Range(lo, hi));
  }

  // --name NAME, one of `choices`, each standing for a value of *field.
  template <typename T>
  CLI::Option* Choice(const std::string& name, T* field,
                      std::vector<std::pair<std::string, T>> choices, const std::string& help) {
    auto shared = std::make_shared<std::vector<std::pair<std::string, T>>>(std::move(choices));
    std::vector<std::string> names;
    for (const auto& c : *shared) names.push_back(c.first);
    auto name_of = [field, shared] {
      for (const auto& c : *shared)
        if (c.second == *field) return c.first;
      return std::string();
    };
    CLI::Option* option = app_.add_option_function<std::string>(
                                  Flag(name),
                                  [field, shared](const std::string& v) {
                                    for (const auto& c : *shared)
                                      if (c.first == v) *field = c.second;
                                  },
                                  help)
                              ->check(
                                  [names](const std::string& v) {
                                    for (const std::string& n : names)
                                      if (n == v) return std::string();
                                    return "expected " + JoinChoices(names) + ", got '" + v + "'";
                                  },
                                  "")
                              ->type_name(JoinChoices(names))
                              ->default_str(name_of());
    Add(name, option, [name_of] { return Json(name_of()); });
    return option;
  }

  // --name / --no-name: *field on / off; its value when declared is the
  // default.
  CLI::Option* Switch(const std::string& name, bool* field, const std::string& help);

  // --name VALUE given as text and kept as *field: `parse` returns "" when
  // it took the text, else what is wrong with it; `format` writes *field
  // back as text (the default shown, and the record).
  template <typename T>
  CLI::Option* Parsed(const std::string& name, T* field, const std::string& type_name,
                      std::function<std::string(const std::string&, T*)> parse,
                      std::function<std::string(const T&)> format, const std::string& help) {
    CLI::Option* option =
        app_.add_option_function<std::string>(
                Flag(name), [field, parse](const std::string& v) { parse(v, field); }, help)
            ->check(
                [parse](const std::string& v) {
                  T scratch{};
                  return parse(v, &scratch);
                },
                "")
            ->type_name(type_name)
            ->default_str(format(*field));
    Add(name, option, [field, format] { return Json(format(*field)); });
    return option;
  }

  // An input or output path (not recorded).
  CLI::Option* Path(const std::string& name, std::filesystem::path* field, const std::string& help);

  // Every recorded option's current value, by record key.
  Json Record() const;

  // The flag table of docs/stages/<stage>.md: one row per option, in the
  // order declared, with its value type, default and help.
  std::string Markdown() const;

 private:
  struct Entry {
    std::string name;  // without "--"
    CLI::Option* option = nullptr;
    std::function<Json()> value;  // empty: not recorded
    std::string flag_text;        // how the docs write it, e.g. "--x, --no-x"
  };

  static std::string Flag(const std::string& name) { return "--" + name; }
  static std::string JoinChoices(const std::vector<std::string>& names);
  void Add(const std::string& name, CLI::Option* option, std::function<Json()> value,
           std::string flag_text = "");

  CLI::App& app_;
  std::vector<Entry> entries_;
};

}  // namespace docunfold
