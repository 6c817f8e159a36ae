#include "common/option_table.h"

#include <sstream>

namespace docunfold {
namespace {

// A record key for a flag name: "lambda-iso" -> "lambda_iso".
std::string RecordKey(const std::string& name) {
  std::string key = name;
  for (char& c : key)
    if (c == '-') c = '_';
  return key;
}

}  // namespace

std::string OptionTable::JoinChoices(const std::vector<std::string>& names) {
  std::string joined;
  for (const std::string& n : names) joined += (joined.empty() ? "" : "|") + n;
  return joined;
}

void OptionTable::Add(const std::string& name, CLI::Option* option, std::function<Json()> value,
                      std::string flag_text) {
  for (const Entry& e : entries_)
    if (e.name == name) throw std::logic_error("option --" + name + " declared twice");
  entries_.push_back(
      {name, option, std::move(value), flag_text.empty() ? Flag(name) : std::move(flag_text)});
}

CLI::Option* OptionTable::Switch(const std::string& name, bool* field, const std::string& help) {
  const std::string default_text = *field ? "on" : "off";
  CLI::Option* option = app_.add_flag(Flag(name) + ",!--no-" + name, *field, help);
  option->default_str(default_text);
  Add(
      name, option, [field] { return Json(*field); }, Flag(name) + ", --no-" + name);
  return option;
}

CLI::Option* OptionTable::Path(const std::string& name, std::filesystem::path* field,
                               const std::string& help) {
  CLI::Option* option = app_.add_option(Flag(name), *field, help);
  Add(name, option, nullptr);
  return option;
}

Json OptionTable::Record() const {
  Json record = Json::object();
  for (const Entry& e : entries_)
    if (e.value) record[RecordKey(e.name)] = e.value();
  return record;
}

namespace {

// Markdown table cells hold no '|' or line breaks.
std::string Cell(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '|')
      out += "\\|";
    else if (c == '\n')
      out += ' ';
    else
      out += c;
  }
  return out;
}

// CLI11's "FLOAT:FLOAT in [0 - 1]" as "number in [0, 1]".
std::string ReadableType(std::string type) {
  const size_t colon = type.find(':');
  if (colon != std::string::npos) type = type.substr(colon + 1);
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"FLOAT", "number"},
                                 {"INT", "integer"},
                                 {"UINT", "integer"},
                                 {"TEXT", "text"}})
    if (type.compare(0, from.size(), from) == 0 &&
        (type.size() == from.size() || type[from.size()] == ' '))
      type = to + type.substr(from.size());
  const size_t range = type.find(" in [");
  if (range != std::string::npos) {
    const size_t dash = type.find(" - ", range);
    if (dash != std::string::npos) type.replace(dash, 3, ", ");
  }
  return type;
}

}  // namespace

std::string OptionTable::Markdown() const {
  std::ostringstream md;
  md << "| flag | value | default | meaning |\n|---|---|---|---|\n";
  for (const Entry& e : entries_) {
    const bool is_switch = e.option->get_expected_min() == 0;
    const std::string value = is_switch ? "" : ReadableType(e.option->get_type_name());
    std::string fallback = e.option->get_default_str();
    if (e.option->get_required()) fallback = "(required)";
    const std::string help = e.option->get_description();
    md << "| `" << Cell(e.flag_text) << "` | " << Cell(value) << " | "
       << (fallback.empty() ? "" : "`" + Cell(fallback) + "`") << " | " << Cell(help) << " |\n";
  }
  return md.str();
}

}  // namespace docunfold
