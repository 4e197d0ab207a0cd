#include "converter/command_line_typos.h"

#include <algorithm>

namespace vxl {
namespace {

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace

std::string nearest_name(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(2, word.size() / 3) + 1;
  for (const std::string& c : candidates)
    if (const std::size_t d = edit_distance(word, c); d < best_distance) best = c, best_distance = d;
  return best;
}

std::string typo_message(const CLI::App& app, int argc, const char* const* argv) {
  const CLI::App* where = &app;
  bool positional_seen = false;
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--") break;
    if (word.rfind("--", 0) == 0) {
      const std::string name = word.substr(0, word.find('='));
      if (where->get_option_no_throw(name) != nullptr) continue;
      std::vector<std::string> known;
      for (const CLI::Option* o : where->get_options())
        for (const std::string& l : o->get_lnames()) known.push_back("--" + l);
      const std::string near = nearest_name(name, known);
      const std::string program = argv[0] ? std::string(argv[0]).substr(std::string(argv[0]).rfind('/') + 1) : "";
      const std::string command = where == &app ? program : program + " " + where->get_name();
      return "unknown option " + name + (near.empty() ? "" : "; did you mean " + near + "?") + " (" + command +
             " --help lists them)";
    }
    if (word[0] == '-' || positional_seen) continue;
    // The first plain word after the program names the subcommand, where there are subcommands.
    const std::vector<const CLI::App*> subcommands = where->get_subcommands([](const CLI::App*) { return true; });
    if (subcommands.empty()) {
      positional_seen = true;
      continue;
    }
    const auto named =
        std::find_if(subcommands.begin(), subcommands.end(), [&](const CLI::App* s) { return s->check_name(word); });
    if (named != subcommands.end()) {
      where = *named;
      continue;
    }
    std::vector<std::string> names;
    for (const CLI::App* s : subcommands) names.push_back(s->get_name());
    const std::string near = nearest_name(word, names);
    return "unknown command '" + word + "'" + (near.empty() ? "" : "; did you mean '" + near + "'?") +
           " (commands: " + joined(names) + ")";
  }
  return "";
}

}  // namespace vxl
