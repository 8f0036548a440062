/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/sim/yaml_lite.h>

#include <cctype>
#include <sstream>

namespace pcl_movers {
namespace sim {

const YamlNode* YamlNode::find(const std::string& key) const {
  for (const auto& kv : map)
    if (kv.first == key) return &kv.second;
  return nullptr;
}

namespace {

struct Line {
  std::size_t number;  // 1-based
  std::size_t indent;
  std::string text;  // without indentation and comment, right-trimmed
};

std::string rtrim(const std::string& s) {
  std::size_t e = s.size();
  while (e > 0 && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(0, e);
}

std::string trim(const std::string& s) {
  std::size_t b = 0;
  while (b < s.size() && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  return rtrim(s.substr(b));
}

class Parser {
 public:
  Parser(const std::string& text, const std::string& file) : file_(file) { split(text); }

  YamlNode parse() {
    if (lines_.empty()) {
      YamlNode empty;
      empty.kind = YamlNode::Kind::Map;
      empty.line = 1;
      return empty;
    }
    if (lines_[0].indent != 0) fail(lines_[0].number, "the first line must not be indented");
    std::size_t i = 0;
    YamlNode root = parseBlock(i, 0);
    if (i < lines_.size()) fail(lines_[i].number, "unexpected indentation or content");
    return root;
  }

 private:
  [[noreturn]] void fail(std::size_t line, const std::string& why) const {
    throw InputError(file_, line, why);
  }

  // Splits into logical lines: comments removed, blank lines dropped, flow collections that
  // span several lines joined, tabs in indentation rejected (YAML forbids them).
  void split(const std::string& text) {
    std::istringstream in(text);
    std::string raw;
    std::size_t number = 0;
    int depth = 0;  // open [ { of a flow collection continued on the next line
    while (std::getline(in, raw)) {
      ++number;
      if (!raw.empty() && raw.back() == '\r') raw.pop_back();
      std::string content;
      char quote = 0;
      for (std::size_t k = 0; k < raw.size(); ++k) {
        const char c = raw[k];
        if (quote) {
          if (c == quote)
            quote = 0;
          else if (c == '\\' && quote == '"' && k + 1 < raw.size())
            content += raw[k++];
        } else if (c == '"' || c == '\'') {
          quote = c;
        } else if (c == '#' && (k == 0 || std::isspace(static_cast<unsigned char>(raw[k - 1])))) {
          break;
        } else if (c == '[' || c == '{') {
          ++depth;
        } else if (c == ']' || c == '}') {
          --depth;
        }
        content += c;
      }
      if (quote) fail(number, "unterminated quoted string");
      if (depth < 0) fail(number, "unbalanced ']' or '}'");
      std::size_t indent = 0;
      while (indent < content.size() && (content[indent] == ' ' || content[indent] == '\t')) {
        if (content[indent] == '\t') fail(number, "tab in indentation (use spaces)");
        ++indent;
      }
      const std::string body = rtrim(content.substr(indent));
      if (body.empty()) continue;
      if (continuing_) {
        lines_.back().text += " " + body;
      } else {
        lines_.push_back({number, indent, body});
      }
      continuing_ = depth > 0;
    }
    if (depth > 0) fail(number, "unterminated '[' or '{' at end of file");
  }

  static bool isSequenceItem(const std::string& text) {
    return text == "-" || (text.size() >= 2 && text[0] == '-' && text[1] == ' ');
  }

  // Position of the ':' that separates a mapping key, or npos (outside quotes and brackets).
  static std::size_t keySeparator(const std::string& text) {
    if (text.empty() || text[0] == '[' || text[0] == '{' || text[0] == '"' || text[0] == '\'')
      return std::string::npos;
    for (std::size_t k = 0; k < text.size(); ++k) {
      if (text[k] == ':' && (k + 1 == text.size() || text[k + 1] == ' ')) return k;
      if (text[k] == '[' || text[k] == '{' || text[k] == '"') return std::string::npos;
    }
    return std::string::npos;
  }

  YamlNode parseBlock(std::size_t& i, std::size_t indent) {
    if (isSequenceItem(lines_[i].text)) return parseSequence(i, indent);
    return parseMap(i, indent);
  }

  YamlNode parseSequence(std::size_t& i, std::size_t indent) {
    YamlNode node;
    node.kind = YamlNode::Kind::Sequence;
    node.line = lines_[i].number;
    while (i < lines_.size() && lines_[i].indent == indent && isSequenceItem(lines_[i].text)) {
      Line& line = lines_[i];
      std::string rest = line.text.size() > 1 ? line.text.substr(2) : std::string();
      std::size_t lead = 0;
      while (lead < rest.size() && rest[lead] == ' ') ++lead;
      rest = rest.substr(lead);
      if (rest.empty()) {
        ++i;
        if (i < lines_.size() && lines_[i].indent > indent) {
          node.sequence.push_back(parseBlock(i, lines_[i].indent));
        } else {
          YamlNode null;
          null.line = line.number;
          node.sequence.push_back(null);
        }
      } else if (isSequenceItem(rest) || keySeparator(rest) != std::string::npos) {
        // "- key: value" starts a mapping whose keys are aligned with "key".
        line.indent = indent + 2 + lead;
        line.text = rest;
        node.sequence.push_back(parseBlock(i, line.indent));
      } else {
        node.sequence.push_back(parseInline(rest, line.number));
        ++i;
      }
    }
    if (i < lines_.size() && lines_[i].indent > indent)
      fail(lines_[i].number, "unexpected indentation");
    return node;
  }

  YamlNode parseMap(std::size_t& i, std::size_t indent) {
    YamlNode node;
    node.kind = YamlNode::Kind::Map;
    node.line = lines_[i].number;
    while (i < lines_.size() && lines_[i].indent == indent) {
      const Line line = lines_[i];
      if (isSequenceItem(line.text))
        fail(line.number, "a '- ' list item where a 'key: value' line was expected");
      const std::size_t sep = keySeparator(line.text);
      if (sep == std::string::npos)
        fail(line.number, "expected 'key: value', got '" + line.text + "'");
      const std::string key = trim(line.text.substr(0, sep));
      if (key.empty()) fail(line.number, "empty key");
      if (node.find(key)) fail(line.number, "duplicate key '" + key + "'");
      const std::string value = trim(line.text.substr(sep + 1));
      ++i;
      YamlNode child;
      if (!value.empty()) {
        child = parseInline(value, line.number);
      } else if (i < lines_.size() && lines_[i].indent > indent) {
        child = parseBlock(i, lines_[i].indent);
      } else if (i < lines_.size() && lines_[i].indent == indent &&
                 isSequenceItem(lines_[i].text)) {
        child = parseSequence(i, indent);  // "key:\n- a\n- b" (sequence not indented)
      } else {
        child.line = line.number;  // "key:" with nothing: null
      }
      node.map.emplace_back(key, std::move(child));
    }
    if (i < lines_.size() && lines_[i].indent > indent)
      fail(lines_[i].number, "unexpected indentation");
    return node;
  }

  // ---- flow values on one logical line
  YamlNode parseInline(const std::string& text, std::size_t line) {
    std::size_t pos = 0;
    YamlNode node = parseFlow(text, pos, line, false);
    skipSpaces(text, pos);
    if (pos != text.size()) fail(line, "unexpected '" + text.substr(pos) + "' after value");
    return node;
  }

  static void skipSpaces(const std::string& t, std::size_t& pos) {
    while (pos < t.size() && std::isspace(static_cast<unsigned char>(t[pos]))) ++pos;
  }

  YamlNode parseFlow(const std::string& t, std::size_t& pos, std::size_t line, bool nested) {
    skipSpaces(t, pos);
    YamlNode node;
    node.line = line;
    if (pos >= t.size()) fail(line, "missing value");
    if (t[pos] == '[') {
      node.kind = YamlNode::Kind::Sequence;
      ++pos;
      skipSpaces(t, pos);
      if (pos < t.size() && t[pos] == ']') {
        ++pos;
        return node;
      }
      for (;;) {
        node.sequence.push_back(parseFlow(t, pos, line, true));
        skipSpaces(t, pos);
        if (pos < t.size() && t[pos] == ',') {
          ++pos;
          continue;
        }
        if (pos < t.size() && t[pos] == ']') {
          ++pos;
          return node;
        }
        fail(line, "expected ',' or ']' in a [ ] list");
      }
    }
    if (t[pos] == '{') {
      node.kind = YamlNode::Kind::Map;
      ++pos;
      skipSpaces(t, pos);
      if (pos < t.size() && t[pos] == '}') {
        ++pos;
        return node;
      }
      for (;;) {
        skipSpaces(t, pos);
        const std::size_t colon = t.find(':', pos);
        if (colon == std::string::npos) fail(line, "expected 'key: value' in a { } mapping");
        const std::string key = trim(t.substr(pos, colon - pos));
        if (key.empty() || key.find_first_of(",{}[]") != std::string::npos)
          fail(line, "malformed key in a { } mapping");
        if (node.find(key)) fail(line, "duplicate key '" + key + "'");
        pos = colon + 1;
        node.map.emplace_back(key, parseFlow(t, pos, line, true));
        skipSpaces(t, pos);
        if (pos < t.size() && t[pos] == ',') {
          ++pos;
          continue;
        }
        if (pos < t.size() && t[pos] == '}') {
          ++pos;
          return node;
        }
        fail(line, "expected ',' or '}' in a { } mapping");
      }
    }
    node.kind = YamlNode::Kind::Scalar;
    if (t[pos] == '"' || t[pos] == '\'') {
      const char q = t[pos++];
      node.quoted = true;
      for (;;) {
        if (pos >= t.size()) fail(line, "unterminated quoted string");
        const char c = t[pos++];
        if (c == q) {
          if (q == '\'' && pos < t.size() && t[pos] == '\'') {
            node.scalar += '\'';
            ++pos;
            continue;
          }
          break;
        }
        if (q == '"' && c == '\\' && pos < t.size()) {
          const char e = t[pos++];
          node.scalar += e == 'n' ? '\n' : e == 't' ? '\t' : e;
          continue;
        }
        node.scalar += c;
      }
      return node;
    }
    const std::size_t start = pos;
    while (pos < t.size() && !(nested && (t[pos] == ',' || t[pos] == ']' || t[pos] == '}'))) ++pos;
    node.scalar = trim(t.substr(start, pos - start));
    if (node.scalar.empty()) fail(line, "missing value");
    if (!nested && (node.scalar.find(": ") != std::string::npos))
      fail(line, "unexpected ': ' in value '" + node.scalar + "' (nested mapping on one line?)");
    if (node.scalar == "~" || node.scalar == "null") node.kind = YamlNode::Kind::Null;
    return node;
  }

  std::string file_;
  std::vector<Line> lines_;
  bool continuing_ = false;
};

}  // namespace

YamlNode parseYaml(const std::string& text, const std::string& file_name) {
  return Parser(text, file_name).parse();
}

}  // namespace sim
}  // namespace pcl_movers
