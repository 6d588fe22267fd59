// The help of `viosfm` and its subcommands, in two tiers: `--help` shows
// what a user needs, by section; `--help-all` shows everything (every flag
// of a subcommand, or every subcommand of the program, the developer tools
// included), each in its section. Help text is wrapped to the terminal's
// usual width.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace viosfm::cli {

// Lines of help are wrapped to this many columns.
inline constexpr size_t kHelpWidth = 100;

struct HelpSection {
  std::string title;
  // Shown by --help (true) or by --help-all only (false).
  bool in_help = true;
  // Flags ("--out") of a subcommand, or subcommands ("run") of the program.
  std::vector<std::string> names;
};

// Puts each flag of `command` into its section and adds --help-all (to the
// first section shown by --help). Every flag is named by one section, or is
// hidden already (a former name kept working): a flag left out, or a name
// that is not a flag of `command`, is a bug (VIOSFM_CHECK). The order of
// the sections in the help is that in which their first flag was added.
void SetOptionSections(CLI::App* command, const std::vector<HelpSection>& sections);

// The same for the subcommands of `app`; --help-all shows the sections
// hidden from --help.
void SetSubcommandSections(CLI::App* app, const std::vector<HelpSection>& sections);

// CLI11's formatter with descriptions wrapped to kHelpWidth columns.
class HelpFormatter : public CLI::Formatter {
 public:
  HelpFormatter();
  std::string make_option_desc(const CLI::Option* option) const override;
  // A subcommand in its parent's list: the first sentence of its
  // description (the subcommand's own --help shows all of it).
  std::string make_subcommand(const CLI::App* sub) const override;
  std::string make_description(const CLI::App* app) const override;
  std::string make_footer(const CLI::App* app) const override;
};

// The first sentence of `text` (up to the first ". "), or all of it.
std::string FirstSentence(const std::string& text);

// `text` broken into lines of at most `width` characters at spaces (a
// longer word stays whole); the line breaks already in it are kept.
std::string WrapText(const std::string& text, size_t width);

}  // namespace viosfm::cli
