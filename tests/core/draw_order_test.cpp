// Draws from one generator in a single expression, e.g. Vec<2>(rng.normal(), rng.normal()): C++
// leaves the order in which function arguments (and the operands of + or *) are evaluated
// unspecified, so g++ and clang++ may assign the draws differently and a run stops being
// reproducible across compilers. The sources must draw in separate statements or with one
// normal_vector<N>() call instead; this test scans every C++ file of the repository for it.
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

bool is_word(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

/// The text with comments and string and character literals blanked out (newlines kept, so that
/// line numbers stay right).
std::string code_only(const std::string& text) {
  std::string out = text;
  std::size_t i = 0;
  auto blank = [&out](std::size_t from, std::size_t to) {
    for (std::size_t k = from; k < to && k < out.size(); ++k)
      if (out[k] != '\n') out[k] = ' ';
  };
  while (i < text.size()) {
    if (text.compare(i, 2, "//") == 0) {
      const std::size_t end = text.find('\n', i);
      blank(i, end == std::string::npos ? text.size() : end);
      i = end == std::string::npos ? text.size() : end;
    } else if (text.compare(i, 2, "/*") == 0) {
      const std::size_t end = text.find("*/", i + 2);
      const std::size_t stop = end == std::string::npos ? text.size() : end + 2;
      blank(i, stop);
      i = stop;
    } else if (text.compare(i, 2, "R\"") == 0 && (i == 0 || !is_word(text[i - 1]))) {
      // R"delimiter( ... )delimiter"
      const std::size_t open = text.find('(', i + 2);
      if (open == std::string::npos) break;
      std::string close = ")";
      close.append(text, i + 2, open - i - 2).push_back('"');
      const std::size_t end = text.find(close, open);
      const std::size_t stop = end == std::string::npos ? text.size() : end + close.size();
      blank(i, stop);
      i = stop;
    } else if (text[i] == '"' || text[i] == '\'') {
      const char quote = text[i];
      std::size_t j = i + 1;
      while (j < text.size() && text[j] != quote && text[j] != '\n') j += text[j] == '\\' ? 2 : 1;
      blank(i, j + 1);
      i = j + 1;
    } else {
      ++i;
    }
  }
  return out;
}

/// The generators drawn from in `piece`: for every `obj.normal(`, `obj.uniform(` or
/// `obj.normal_vector<...>(` (also through ->), the name `obj`, once per call.
std::vector<std::string> draws(const std::string& piece) {
  std::vector<std::string> out;
  for (const char* method : {"normal", "uniform", "normal_vector"}) {
    const std::string m(method);
    for (std::size_t at = piece.find(m); at != std::string::npos; at = piece.find(m, at + 1)) {
      std::size_t after = at + m.size();
      if (after < piece.size() && is_word(piece[after])) continue;  // normal_vector for normal
      if (after < piece.size() && piece[after] == '<') after = piece.find('>', after) + 1;
      while (after < piece.size() && piece[after] == ' ') ++after;
      if (after == 0 || after >= piece.size() || piece[after] != '(') continue;
      std::size_t before = at;
      if (before >= 1 && piece[before - 1] == '.') {
        before -= 1;
      } else if (before >= 2 && piece.compare(before - 2, 2, "->") == 0) {
        before -= 2;
      } else {
        continue;
      }
      std::size_t start = before;
      while (start > 0 && is_word(piece[start - 1])) --start;
      if (start < before) out.push_back(piece.substr(start, before - start));
    }
  }
  return out;
}

/// A ':' that is not part of '::' (the else branch of ?:, also labels and bit fields).
bool is_branch_colon(const std::string& code, std::size_t i) {
  return code[i] == ':' && (i == 0 || code[i - 1] != ':') &&
         (i + 1 == code.size() || code[i + 1] != ':');
}

/// The pieces of code whose evaluation order among each other C++ does not fix: statements cut
/// at ; { } (braced initializer lists are evaluated in order), then at the sequence points
/// inside a statement (the comma at the top level of a statement, && || ?).
std::vector<std::pair<std::size_t, std::string>> unsequenced_pieces(const std::string& code) {
  std::vector<std::pair<std::size_t, std::string>> out;
  std::size_t line = 1, piece_line = 1;
  std::string piece;
  int depth = 0;  // parentheses and brackets within the current statement
  auto flush = [&] {
    out.emplace_back(piece_line, piece);
    piece.clear();
    piece_line = line;
  };
  for (std::size_t i = 0; i < code.size(); ++i) {
    const char c = code[i];
    if (c == ';' || c == '{' || c == '}') {
      flush();
      depth = 0;
    } else if ((c == ',' && depth == 0) || c == '?' || is_branch_colon(code, i) ||
               (i + 1 < code.size() &&
                (code.compare(i, 2, "&&") == 0 || code.compare(i, 2, "||") == 0))) {
      flush();
    } else {
      if (c == '(' || c == '[') ++depth;
      if ((c == ')' || c == ']') && depth > 0) --depth;
      piece += c;
    }
    if (c == '\n') {
      ++line;
      if (piece.find_first_not_of(" \t\n") == std::string::npos) piece_line = line;
    }
  }
  flush();
  return out;
}

/// "file:line: expression" for every piece that draws twice or more from one generator.
std::vector<std::string> find_unordered_draws(const std::string& text, const std::string& name) {
  std::vector<std::string> found;
  for (const auto& [line, piece] : unsequenced_pieces(code_only(text))) {
    std::map<std::string, int> count;
    for (const auto& g : draws(piece))
      if (++count[g] == 2) {
        std::string flat;  // one line, runs of blanks as one space
        for (char c : piece)
          if (!std::isspace(static_cast<unsigned char>(c)))
            flat += c;
          else if (!flat.empty() && flat.back() != ' ')
            flat += ' ';
        found.push_back(name + ":" + std::to_string(line) + ": " + g + " in '" + flat + "'");
      }
  }
  return found;
}

TEST(DrawOrder, TheScanFindsTwoDrawsFromOneGeneratorInOneExpression) {
  EXPECT_EQ(find_unordered_draws("x = Vec<2>(rng.normal(), rng.normal());", "a").size(), 1u);
  EXPECT_EQ(
      find_unordered_draws("p = Pose(10 * g->uniform() - 5,\n  g->uniform(), 0);", "b").size(), 1u);
  EXPECT_EQ(find_unordered_draws("s = 2.0 * r.uniform() * r.normal_vector<2>();", "c").size(), 1u);
  // Sequenced or different generators: declarators, braced lists, && || ?:, comments.
  for (const char* ok :
       {"const double a = rng.uniform(), b = rng.uniform();",
        "Mount m{rng.uniform(), rng.uniform()};",
        "if (rng.uniform() < 0.5 && rng.uniform() > 0.1) {}", "v = a.normal() + b.normal();",
        "x = rng.uniform() < 0.5 ? rng.normal() : rng.uniform();",
        "// Vec<2>(rng.normal(), rng.normal())", "f(\"rng.normal(), rng.normal()\");",
        "f(R\"x(rng.normal(), rng.normal())x\");"})
    EXPECT_TRUE(find_unordered_draws(ok, "ok").empty()) << ok;
}

TEST(DrawOrder, NoExpressionOfTheRepositoryDrawsTwiceFromOneGenerator) {
  const std::filesystem::path root(IMPLICIT_SOURCE_DIR);
  std::vector<std::string> found;
  std::size_t files = 0;
  for (const char* dir :
       {"include", "src", "apps", "experiments", "examples", "bench", "tests", "python", "fuzz"}) {
    if (!std::filesystem::is_directory(root / dir)) continue;
    for (const auto& e : std::filesystem::recursive_directory_iterator(root / dir)) {
      const auto ext = e.path().extension();
      if (!e.is_regular_file() || (ext != ".cpp" && ext != ".hpp")) continue;
      std::ifstream in(e.path());
      std::stringstream text;
      text << in.rdbuf();
      ++files;
      for (auto& f :
           find_unordered_draws(text.str(), std::filesystem::relative(e.path(), root).string()))
        found.push_back(std::move(f));
    }
  }
  EXPECT_GT(files, 100u);
  for (const auto& f : found)
    ADD_FAILURE() << f << ": two draws whose order the compiler chooses; draw in separate "
                  << "statements (or declarators), or with one normal_vector<N>() call";
}

}  // namespace
