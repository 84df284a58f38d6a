#include "tactile/config/yaml.hpp"

#include <algorithm>
#include <cmath>

#include "tactile/util/files.hpp"
#include "tactile/util/text.hpp"

namespace tactile::config {

using util::one_line;

Node::Node(YAML::Node node, std::string path, std::shared_ptr<const std::string> source)
    : node_(std::move(node)), path_(std::move(path)), source_(std::move(source)) {}

void Node::fail(const std::string& what) const {
  std::string where = *source_;
  const YAML::Mark m = node_.IsDefined() ? node_.Mark() : YAML::Mark::null_mark();
  if (m.line >= 0) where += ":" + std::to_string(m.line + 1);
  if (path_.empty()) throw ConfigError(one_line(where + ": " + what));
  throw ConfigError(one_line(where + ": key '" + path_ + "': " + what));
}

std::string Node::text() const {
  if (!node_.IsDefined() || node_.IsNull()) return "<empty>";
  if (node_.IsMap()) return "<map>";
  if (node_.IsSequence()) return "<sequence>";
  // Quoted on one line whatever the file holds: control characters and bytes beyond ASCII
  // are escaped, and a long value is cut.
  std::string out = "'";
  const std::string& v = node_.Scalar();
  for (std::size_t i = 0; i < v.size() && i < 80; ++i) {
    const auto c = static_cast<unsigned char>(v[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      static const char* kHex = "0123456789abcdef";
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  if (v.size() > 80) out += "...";
  return out + "'";
}

std::optional<Node> Node::find(std::string_view key) const {
  if (!node_.IsMap()) return std::nullopt;
  const std::string k(key);
  YAML::Node child = node_[k];
  if (!child.IsDefined()) return std::nullopt;
  return Node(child, path_.empty() ? k : path_ + "." + k, source_);
}

Node Node::operator[](std::string_view key) const {
  if (!node_.IsMap()) fail("must be a mapping with key '" + std::string(key) + "', is " + text());
  auto child = find(key);
  if (!child) {
    const std::string full = path_.empty() ? std::string(key) : path_ + "." + std::string(key);
    std::string where = *source_;
    if (node_.Mark().line >= 0) where += ":" + std::to_string(node_.Mark().line + 1);
    throw ConfigError(one_line(where + ": key '" + full + "' is missing"));
  }
  return *child;
}

std::size_t Node::size() const {
  if (!node_.IsSequence()) fail("must be a list, is " + text());
  return node_.size();
}

Node Node::at(std::size_t index) const {
  if (!node_.IsSequence()) fail("must be a list, is " + text());
  return Node(node_[index], path_ + "[" + std::to_string(index) + "]", source_);
}

std::string Node::as_string() const {
  if (!node_.IsScalar()) fail("must be a text value, is " + text());
  return node_.Scalar();
}

double Node::as_double() const {
  if (!node_.IsScalar()) fail("must be a number, is " + text());
  double v = 0;
  try {
    v = node_.as<double>();
  } catch (const YAML::Exception&) {
    fail("must be a number, is " + text());
  }
  if (!std::isfinite(v)) fail("must be a finite number, is " + text());
  return v;
}

std::int64_t Node::as_int() const {
  if (!node_.IsScalar()) fail("must be a whole number, is " + text());
  try {
    return node_.as<std::int64_t>();
  } catch (const YAML::Exception&) {
    fail("must be a whole number, is " + text());
  }
}

bool Node::as_bool() const {
  if (!node_.IsScalar()) fail("must be true or false, is " + text());
  try {
    return node_.as<bool>();
  } catch (const YAML::Exception&) {
    fail("must be true or false, is " + text());
  }
}

std::vector<double> Node::as_doubles() const {
  const std::size_t n = size();
  std::vector<double> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    out.push_back(at(i).as_double());
  return out;
}

double Node::get(std::string_view key, double fallback) const {
  auto c = find(key);
  return c ? c->as_double() : fallback;
}
std::int64_t Node::get(std::string_view key, std::int64_t fallback) const {
  auto c = find(key);
  return c ? c->as_int() : fallback;
}
int Node::get(std::string_view key, int fallback) const {
  auto c = find(key);
  if (!c) return fallback;
  const std::int64_t v = c->as_int();
  if (v < INT32_MIN || v > INT32_MAX) c->fail("is out of range: " + c->text());
  return static_cast<int>(v);
}
bool Node::get(std::string_view key, bool fallback) const {
  auto c = find(key);
  return c ? c->as_bool() : fallback;
}
std::string Node::get(std::string_view key, const std::string& fallback) const {
  auto c = find(key);
  return c ? c->as_string() : fallback;
}

std::vector<std::string> Node::keys() const {
  std::vector<std::string> out;
  if (!node_.IsMap()) return out;
  for (const auto& kv : node_)
    out.push_back(kv.first.Scalar());
  return out;
}

namespace {

// "<file>:<line>: unknown key '<key>' in '<section>'<verdict> (did you mean '<closest>'?)", or
// with the known keys listed when none is close.
std::string unknown_key_message(const std::string& source, const YAML::Node& key,
                                const std::string& section, const std::vector<std::string>& known,
                                const char* verdict) {
  std::string msg = source;
  if (key.Mark().line >= 0) msg += ":" + std::to_string(key.Mark().line + 1);
  msg += ": unknown key '" + key.Scalar() + "'";
  if (!section.empty()) msg += " in '" + section + "'";
  msg += verdict;
  const std::string near = util::closest_match(key.Scalar(), known);
  if (!near.empty()) {
    msg += " (did you mean '" + near + "'?)";
  } else if (known.empty()) {
    msg += " (this section takes no keys)";
  } else {
    msg += " (known keys: ";
    for (std::size_t i = 0; i < known.size(); ++i)
      msg += (i == 0 ? "" : ", ") + known[i];
    msg += ")";
  }
  return one_line(msg);
}

bool is_known(const std::string& key, const std::vector<std::string>& known) {
  return std::find(known.begin(), known.end(), key) != known.end();
}

}  // namespace

void Node::refuse_unknown_keys(const std::vector<std::string>& known) const {
  if (!node_.IsMap()) return;
  for (const auto& kv : node_) {
    if (!is_known(kv.first.Scalar(), known))
      throw ConfigError(unknown_key_message(*source_, kv.first, path_, known, ""));
  }
}

std::vector<std::string> Node::unknown_key_warnings(const std::vector<std::string>& known) const {
  std::vector<std::string> out;
  if (!node_.IsMap()) return out;
  for (const auto& kv : node_) {
    if (!is_known(kv.first.Scalar(), known))
      out.push_back(unknown_key_message(*source_, kv.first, path_, known, " ignored"));
  }
  return out;
}

Node parse_yaml(const std::string& text, const std::string& source) {
  auto src = std::make_shared<const std::string>(source);
  try {
    return Node(YAML::Load(text), "", src);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(
        one_line(source + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg));
  }
}

Node load_yaml_file(const std::filesystem::path& path) {
  std::string text;
  try {
    text = util::read_file(path);
  } catch (const std::exception& e) {
    throw ConfigError(one_line(e.what()));
  }
  return parse_yaml(text, path.string());
}

}  // namespace tactile::config
