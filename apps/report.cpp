// The report's document model and its Markdown and HTML renderings.
#include "report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "implicit/core/error.hpp"

namespace implicit::app::report {

void Document::heading(int level, std::string text) {
  Block b;
  b.kind = Block::Kind::kHeading;
  b.level = level;
  b.text = std::move(text);
  blocks_.push_back(std::move(b));
}

void Document::paragraph(std::string text) {
  Block b;
  b.kind = Block::Kind::kParagraph;
  b.text = std::move(text);
  blocks_.push_back(std::move(b));
}

void Document::list(std::vector<std::string> items) {
  Block b;
  b.kind = Block::Kind::kList;
  b.items = std::move(items);
  blocks_.push_back(std::move(b));
}

void Document::table(Table t) {
  Block b;
  b.kind = Block::Kind::kTable;
  b.table = std::move(t);
  blocks_.push_back(std::move(b));
}

void Document::image(std::string src, std::string caption) {
  Block b;
  b.kind = Block::Kind::kImage;
  b.src = std::move(src);
  b.text = std::move(caption);
  blocks_.push_back(std::move(b));
}

void Document::code(std::string text) {
  Block b;
  b.kind = Block::Kind::kCode;
  b.text = std::move(text);
  blocks_.push_back(std::move(b));
}

namespace {

// Markdown table cells cannot contain '|' or line breaks.
std::string md_cell(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '|')
      out += "\\|";
    else if (c == '\n')
      out += ' ';
    else
      out += c;
  }
  return out.empty() ? " " : out;
}

// Inline markup for HTML: `code` and **bold**, everything else escaped.
std::string html_inline(const std::string& s) {
  std::string out;
  bool in_code = false, in_bold = false;
  std::string buffer;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '`') {
      out += in_code ? "</code>" : "<code>";
      in_code = !in_code;
    } else if (!in_code && s[i] == '*' && i + 1 < s.size() && s[i + 1] == '*') {
      out += in_bold ? "</strong>" : "<strong>";
      in_bold = !in_bold;
      ++i;
    } else {
      out += html_escape(std::string(1, s[i]));
    }
  }
  if (in_code) out += "</code>";
  if (in_bold) out += "</strong>";
  return out;
}

std::string slug(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (std::isalnum(static_cast<unsigned char>(c)))
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    else if (!out.empty() && out.back() != '-')
      out += '-';
  }
  while (!out.empty() && out.back() == '-') out.pop_back();
  return out;
}

}  // namespace

std::size_t text_width(const std::string& s) {
  // A code point is one byte that is not a UTF-8 continuation byte (10xxxxxx).
  return static_cast<std::size_t>(std::count_if(
      s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

std::string aligned_columns(const std::vector<std::vector<std::string>>& rows,
                            const std::vector<bool>& right, const std::string& indent) {
  std::vector<std::size_t> width;
  for (const auto& row : rows) {
    if (width.size() < row.size()) width.resize(row.size(), 0);
    for (std::size_t j = 0; j < row.size(); ++j) width[j] = std::max(width[j], text_width(row[j]));
  }
  std::string out;
  for (const auto& row : rows) {
    std::string line = indent;
    for (std::size_t j = 0; j < row.size(); ++j) {
      const std::string pad(width[j] - text_width(row[j]), ' ');
      if (j > 0) line += "  ";
      line += j < right.size() && right[j] ? pad + row[j] : row[j] + pad;
    }
    while (!line.empty() && line.back() == ' ') line.pop_back();
    out += line + "\n";
  }
  return out;
}

std::string html_escape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string Document::markdown() const {
  std::string out;
  for (const auto& b : blocks_) {
    switch (b.kind) {
      case Block::Kind::kHeading:
        out += std::string(static_cast<std::size_t>(std::clamp(b.level, 1, 6)), '#') + " " +
               b.text + "\n\n";
        break;
      case Block::Kind::kParagraph:
        out += b.text + "\n\n";
        break;
      case Block::Kind::kList:
        for (const auto& item : b.items) out += "- " + item + "\n";
        out += "\n";
        break;
      case Block::Kind::kTable: {
        const auto& t = b.table;
        if (!t.caption.empty()) out += "*" + t.caption + "*\n\n";
        out += "|";
        for (const auto& h : t.header) out += fmt::format(" {} |", md_cell(h));
        out += "\n|";
        for (std::size_t i = 0; i < t.header.size(); ++i) out += i == 0 ? "---|" : "---:|";
        out += "\n";
        for (const auto& row : t.rows) {
          out += "|";
          for (std::size_t i = 0; i < t.header.size(); ++i)
            out += fmt::format(" {} |", md_cell(i < row.size() ? row[i] : ""));
          out += "\n";
        }
        out += "\n";
        break;
      }
      case Block::Kind::kImage:
        out += "![" + b.text + "](" + b.src + ")\n\n*" + b.text + "*\n\n";
        break;
      case Block::Kind::kCode:
        out += "```\n" + b.text + "\n```\n\n";
        break;
    }
  }
  return out;
}

std::string Document::html(const std::string& title) const {
  std::string out = fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      "<title>{}</title>\n<style>\n"
      "body{{font-family:-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;max-width:72em;"
      "margin:2em auto;padding:0 1em;line-height:1.45;color:#1b1b1b}}\n"
      "h1{{border-bottom:2px solid #ccc;padding-bottom:.2em}}h2{{border-bottom:1px solid #ddd;"
      "margin-top:2em}}\n"
      "table{{border-collapse:collapse;margin:.5em 0 1.5em;font-size:.9em}}"
      "th,td{{border:1px solid #ccc;padding:.25em .6em;text-align:right}}"
      "th{{background:#f3f3f3}}td:first-child,th:first-child{{text-align:left}}"
      "tr:nth-child(even) td{{background:#fafafa}}\n"
      "caption{{caption-side:top;text-align:left;font-style:italic;padding:.3em 0}}\n"
      "code,pre{{font-family:Menlo,Consolas,monospace;font-size:.9em;background:#f5f5f5}}"
      "pre{{padding:.6em;overflow-x:auto}}\n"
      "figure{{margin:1em 0 2em}}figure img{{max-width:100%;border:1px solid #ddd}}"
      "figcaption{{font-style:italic}}\n"
      ".ok{{color:#1a7f37;font-weight:bold}}.failed{{color:#c62828;font-weight:bold}}"
      ".partial{{color:#b26a00;font-weight:bold}}\n"
      "</style>\n</head>\n<body>\n",
      html_escape(title));
  for (const auto& b : blocks_) {
    switch (b.kind) {
      case Block::Kind::kHeading: {
        const int level = std::clamp(b.level, 1, 6);
        out +=
            fmt::format("<h{0} id=\"{1}\">{2}</h{0}>\n", level, slug(b.text), html_inline(b.text));
        break;
      }
      case Block::Kind::kParagraph:
        out += "<p>" + html_inline(b.text) + "</p>\n";
        break;
      case Block::Kind::kList:
        out += "<ul>\n";
        for (const auto& item : b.items) out += "<li>" + html_inline(item) + "</li>\n";
        out += "</ul>\n";
        break;
      case Block::Kind::kTable: {
        const auto& t = b.table;
        out += "<table>\n";
        if (!t.caption.empty()) out += "<caption>" + html_inline(t.caption) + "</caption>\n";
        out += "<thead><tr>";
        for (const auto& h : t.header) out += "<th>" + html_inline(h) + "</th>";
        out += "</tr></thead>\n<tbody>\n";
        for (const auto& row : t.rows) {
          out += "<tr>";
          for (std::size_t i = 0; i < t.header.size(); ++i) {
            const std::string cell = i < row.size() ? row[i] : "";
            std::string cls;
            if (cell == "ok" || cell == "failed" || cell == "partial")
              cls = " class=\"" + cell + "\"";
            out += "<td" + cls + ">" + html_inline(cell) + "</td>";
          }
          out += "</tr>\n";
        }
        out += "</tbody>\n</table>\n";
        break;
      }
      case Block::Kind::kImage:
        out +=
            fmt::format("<figure><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>\n",
                        html_escape(b.src), html_escape(b.text), html_inline(b.text));
        break;
      case Block::Kind::kCode:
        out += "<pre>" + html_escape(b.text) + "</pre>\n";
        break;
    }
  }
  out += "</body>\n</html>\n";
  return out;
}

std::string number(const nlohmann::json& value, int digits) {
  if (!value.is_number()) return "–";
  const double v = value.get<double>();
  if (!std::isfinite(v)) return "–";
  return fmt::format("{:.{}f}", v, digits);
}

std::string spread(const nlohmann::json& result, const std::string& prefix, int digits) {
  auto get = [&](const std::string& key) -> nlohmann::json {
    return result.is_object() && result.contains(key) ? result.at(key) : nlohmann::json();
  };
  const auto mean = get(prefix + "_mean");
  if (!mean.is_number()) return "–";
  std::string s = number(mean, digits);
  const auto sd = get(prefix + "_std");
  if (sd.is_number()) s += " ± " + number(sd, digits);
  std::vector<std::string> notes;
  const double se = standard_error(sd, get("runs").is_number() ? get("runs") : get("datasets"));
  if (std::isfinite(se)) notes.push_back("SE " + format_se(se));
  const auto median = get(prefix + "_median");
  if (median.is_number()) notes.push_back("med " + number(median, digits));
  for (std::size_t i = 0; i < notes.size(); ++i)
    s += (i == 0 ? " (" : ", ") + notes[i] + (i + 1 == notes.size() ? ")" : "");
  return s;
}

double standard_error(const nlohmann::json& sd, const nlohmann::json& n) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!sd.is_number() || !n.is_number()) return nan;
  const double s = sd.get<double>(), k = n.get<double>();
  if (!std::isfinite(s) || s < 0.0 || !(k >= 2.0)) return nan;
  return s / std::sqrt(k);
}

std::string format_se(double se) {
  if (!std::isfinite(se) || se < 0.0) return "–";
  if (se == 0.0) return "0";
  // Two significant digits: decimals = 1 − floor(log10 se), never negative.
  const int decimals = std::max(0, 1 - static_cast<int>(std::floor(std::log10(se))));
  return fmt::format("{:.{}f}", se, decimals);
}

std::string agreement(const Estimate& ours, const Estimate& reference) {
  const double combined = std::hypot(ours.se, reference.se);
  if (!std::isfinite(ours.mean) || !std::isfinite(reference.mean) || !std::isfinite(combined) ||
      ours.se < 0.0 || reference.se < 0.0 || combined <= 0.0)
    return "–";
  return std::abs(ours.mean - reference.mean) <= kAgreementSigmas * combined ? "✓" : "✗";
}

Table read_csv_table(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ParseError(fmt::format("{}: cannot open the file", file.string()));
  auto split = [](const std::string& line) {
    std::vector<std::string> fields;
    std::string field;
    std::istringstream ss(line);
    while (std::getline(ss, field, ',')) fields.push_back(field);
    if (!line.empty() && line.back() == ',') fields.emplace_back();
    return fields;
  };
  Table t;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    auto fields = split(line);
    if (t.header.empty()) {
      t.header = std::move(fields);
      continue;
    }
    if (fields.size() != t.header.size())
      throw ParseError(fmt::format("{}:{}: expected {} fields as in the header, got {}",
                                   file.string(), line_no, t.header.size(), fields.size()));
    t.rows.push_back(std::move(fields));
  }
  if (t.header.empty())
    throw ParseError(fmt::format("{}: expected a header line, got an empty file", file.string()));
  return t;
}

const nlohmann::json& experiment_runs(const nlohmann::json& results, const std::string& name) {
  static const nlohmann::json empty = nlohmann::json::array();
  if (!results.contains("experiments")) return empty;
  const auto& e = results.at("experiments");
  if (!e.contains(name) || !e.at(name).contains("runs")) return empty;
  return e.at(name).at("runs");
}

}  // namespace implicit::app::report
