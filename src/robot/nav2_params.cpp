// ROS 2 parameter files (nav2_params.hpp), with yaml-cpp.
#include "implicit/robot/nav2_params.hpp"

#include <set>
#include <string>
#include <utility>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "implicit/core/error.hpp"
#include "implicit/robot/csv_table.hpp"

namespace implicit::robot {
namespace {

// A parameter file is a few kB; a deep nesting or a huge list is not one (and would make the
// flattening below recurse or join without bound).
constexpr int kNav2MaxDepth = 8;
constexpr std::size_t kNav2MaxListItems = 4096;

int nav2_line(const YAML::Node& n) { return n.Mark().is_null() ? 0 : n.Mark().line + 1; }

[[noreturn]] void nav2_fail(const std::string& name, int line, const std::string& what) {
  if (line > 0) throw ParseError(fmt::format("{}:{}: {}", name, line, what));
  throw ParseError(fmt::format("{}: {}", name, what));
}

// "amcl", "/amcl", "/robot1/amcl" and "/**/amcl" all name the node "amcl".
bool nav2_names_node(const std::string& written, const std::string& node) {
  if (written == node) return true;
  return written.size() > node.size() && written.ends_with(node) &&
         written[written.size() - node.size() - 1] == '/';
}

class Nav2Flattener {
 public:
  Nav2Flattener(const std::string& name, Nav2Parameters& out) : name_(name), out_(out) {}

  void add(const std::string& key, const YAML::Node& value, int depth) {
    const int line = nav2_line(value);
    if (depth > kNav2MaxDepth)
      nav2_fail(name_, line,
                fmt::format("{}: expected at most {} levels of nesting", key, kNav2MaxDepth));
    if (value.IsMap()) {
      for (const auto& kv : value) add(key + "." + scalar_key(kv.first), kv.second, depth + 1);
      return;
    }
    Nav2Parameter p;
    p.key = key;
    p.line = line;
    if (value.IsSequence()) {
      p.is_list = true;
      std::size_t items = 0;
      for (const auto& item : value) {
        if (!item.IsScalar())
          nav2_fail(name_, nav2_line(item),
                    fmt::format("{}: expected a list of numbers or words, got a nested list or "
                                "mapping",
                                key));
        if (++items > kNav2MaxListItems)
          nav2_fail(name_, line,
                    fmt::format("{}: expected at most {} items", key, kNav2MaxListItems));
        p.value += (p.value.empty() ? "" : " ") + item.Scalar();
      }
    } else if (value.IsScalar()) {
      p.value = value.Scalar();
    }  // a key without a value (null) keeps an empty value
    if (!seen_.insert(key).second)
      nav2_fail(name_, line, fmt::format("{}: the key is given twice", key));
    out_.entries.push_back(std::move(p));
  }

  std::string scalar_key(const YAML::Node& k) const {
    if (!k.IsScalar())
      nav2_fail(name_, nav2_line(k), "expected parameter names, got a list or mapping as a key");
    return k.Scalar();
  }

 private:
  const std::string& name_;
  Nav2Parameters& out_;
  std::set<std::string> seen_;
};

}  // namespace

const Nav2Parameter* Nav2Parameters::find(std::string_view key) const {
  for (const auto& e : entries)
    if (e.key == key) return &e;
  return nullptr;
}

Nav2Parameters parse_nav2_parameters(std::string_view text, const std::string& name,
                                     const std::string& node) {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    nav2_fail(name, e.mark.is_null() || e.mark.line < 0 ? 0 : e.mark.line + 1,
              fmt::format("expected a ROS 2 parameter file (YAML), got a syntax error: {}",
                          printable(e.msg)));
  }
  const std::string expected = fmt::format(
      "expected a ROS 2 parameter file with a '{}:' block holding 'ros__parameters:'", node);
  if (!root.IsMap())
    nav2_fail(name, 0,
              fmt::format("{}, got {}", expected,
                          root.IsNull() ? "an empty file" : "a list or a single value"));
  Nav2Parameters out;
  out.source = name;
  Nav2Flattener flatten(name, out);
  for (const auto& kv : root) {
    const std::string written = flatten.scalar_key(kv.first);
    if (!nav2_names_node(written, node)) continue;
    const YAML::Node block = kv.second;
    if (!block.IsMap() || !block["ros__parameters"])
      nav2_fail(name, nav2_line(kv.first),
                fmt::format("{}: expected 'ros__parameters:' under it", written));
    const YAML::Node params = block["ros__parameters"];
    if (!params.IsMap())
      nav2_fail(name, nav2_line(params),
                fmt::format("{}: ros__parameters: expected a mapping of parameter names to "
                            "values, got {}",
                            written, params.IsNull() ? "nothing" : "a list or a single value"));
    out.node = written;
    for (const auto& p : params) flatten.add(flatten.scalar_key(p.first), p.second, 0);
    return out;
  }
  nav2_fail(name, 0, fmt::format("{}, got no '{}' block", expected, node));
}

Nav2Parameters read_nav2_parameters(const std::filesystem::path& path, const std::string& node) {
  return parse_nav2_parameters(read_text_file(path, std::size_t{1} << 20), path.string(), node);
}

}  // namespace implicit::robot
