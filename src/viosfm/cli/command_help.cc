#include "viosfm/cli/command_help.h"

#include <algorithm>
#include <memory>
#include <sstream>
#include <utility>

#include "viosfm/util/errors.h"

namespace viosfm::cli {
namespace {

// What --help-all shows besides --help: each hidden item with its section.
template <class Item>
using HiddenItems = std::vector<std::pair<Item*, std::string>>;

// Adds --help-all to `command`: it gives each hidden item its section, then
// asks for the help (CLI11 prints the help of the subcommand it was given to).
template <class Item>
CLI::Option* AddHelpAllFlag(CLI::App* command, std::shared_ptr<HiddenItems<Item>> hidden,
                            const std::string& what) {
  return command->add_flag_callback(
      "--help-all",
      [hidden] {
        for (auto& [item, title] : *hidden) item->group(title);
        throw CLI::CallForHelp();
      },
      "Print the help with " + what + " and exit");
}

const HelpSection& FirstShown(const std::vector<HelpSection>& sections) {
  for (const HelpSection& section : sections) {
    if (section.in_help) return section;
  }
  VIOSFM_CHECK(false) << "help sections: none is shown by --help";
  return sections.front();
}

}  // namespace

void SetOptionSections(CLI::App* command, const std::vector<HelpSection>& sections) {
  auto hidden = std::make_shared<HiddenItems<CLI::Option>>();
  std::vector<const CLI::Option*> placed;
  for (const HelpSection& section : sections) {
    for (const std::string& name : section.names) {
      CLI::Option* option = command->get_option_no_throw(name);
      VIOSFM_CHECK(option != nullptr) << command->get_name() << ": no flag " << name;
      VIOSFM_CHECK(!option->get_group().empty())
          << command->get_name() << ": " << name << " is hidden already";
      placed.push_back(option);
      if (section.in_help) {
        option->group(section.title);
      } else {
        hidden->emplace_back(option, section.title);
      }
    }
  }
  const std::string first = FirstShown(sections).title;
  CLI::Option* help = command->get_help_ptr();
  if (help != nullptr) {
    help->group(first);
    placed.push_back(help);
  }
  placed.push_back(AddHelpAllFlag(command, hidden, "every flag")->group(first));
  for (const CLI::Option* option : command->get_options()) {
    if (option->get_positional() || option->get_group().empty()) continue;
    VIOSFM_CHECK(std::find(placed.begin(), placed.end(), option) != placed.end())
        << command->get_name() << ": flag " << option->get_name(false, true)
        << " has no help section";
  }
  // Hidden last, so that their names could still be found above.
  for (auto& [option, title] : *hidden) option->group("");
}

void SetSubcommandSections(CLI::App* app, const std::vector<HelpSection>& sections) {
  auto hidden = std::make_shared<HiddenItems<CLI::App>>();
  size_t num_placed = 0;
  for (const HelpSection& section : sections) {
    for (const std::string& name : section.names) {
      CLI::App* sub = app->get_subcommand(name);  // throws for a missing one: a bug
      ++num_placed;
      if (section.in_help) {
        sub->group(section.title);
      } else {
        sub->group("");
        hidden->emplace_back(sub, section.title);
      }
    }
  }
  VIOSFM_CHECK(num_placed == app->get_subcommands({}).size())
      << "every subcommand of " << app->get_name() << " belongs to one help section";
  AddHelpAllFlag(app, hidden, "the developer tools too");
}

std::string FirstSentence(const std::string& text) {
  const size_t end = text.find(". ");
  return end == std::string::npos ? text : text.substr(0, end + 1);
}

std::string WrapText(const std::string& text, size_t width) {
  std::ostringstream out;
  std::istringstream lines(text);
  std::string line;
  bool first_line = true;
  while (std::getline(lines, line)) {
    if (!first_line) out << '\n';
    first_line = false;
    // Leading spaces (an indented example) are kept.
    const size_t indent = line.find_first_not_of(' ');
    if (indent == std::string::npos) continue;
    std::istringstream words(line.substr(indent));
    std::string word;
    size_t column = 0;
    out << std::string(indent, ' ');
    column = indent;
    bool first_word = true;
    while (words >> word) {
      if (!first_word && column + 1 + word.size() > width) {
        out << '\n' << std::string(indent, ' ');
        column = indent;
        first_word = true;
      }
      if (!first_word) {
        out << ' ';
        ++column;
      }
      out << word;
      column += word.size();
      first_word = false;
    }
  }
  return out.str();
}

HelpFormatter::HelpFormatter() {
  column_width(32);
}

std::string HelpFormatter::make_option_desc(const CLI::Option* option) const {
  return WrapText(option->get_description(), kHelpWidth - get_column_width());
}

std::string HelpFormatter::make_subcommand(const CLI::App* sub) const {
  std::stringstream out;
  CLI::detail::format_help(
      out, sub->get_display_name(true),
      WrapText(FirstSentence(sub->get_description()), kHelpWidth - get_column_width()),
      get_column_width());
  return out.str();
}

std::string HelpFormatter::make_footer(const CLI::App* app) const {
  const std::string footer = app->get_footer();
  return footer.empty() ? std::string() : WrapText(footer, kHelpWidth) + "\n";
}

std::string HelpFormatter::make_description(const CLI::App* app) const {
  const std::string description = app->get_description();
  return description.empty() ? std::string() : WrapText(description, kHelpWidth) + "\n";
}

}  // namespace viosfm::cli
