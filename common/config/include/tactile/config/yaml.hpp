#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace tactile::config {

// A configuration file that cannot be used. what() is one line that names the file, the key and
// the offending value, e.g. "left.yaml:14: key 'elements[3].radius_px': must be ..., is -2".
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A node of a YAML document that knows its file and key path, so every error can name both.
class Node {
 public:
  Node(YAML::Node node, std::string path, std::shared_ptr<const std::string> source);

  const std::string& path() const { return path_; }
  const std::string& source() const { return *source_; }
  bool is_map() const { return node_.IsMap(); }
  bool is_sequence() const { return node_.IsSequence(); }
  bool is_null() const { return !node_.IsDefined() || node_.IsNull(); }

  // The child under `key`; throws "missing" when absent.
  Node operator[](std::string_view key) const;
  std::optional<Node> find(std::string_view key) const;
  bool has(std::string_view key) const { return find(key).has_value(); }
  std::size_t size() const;          // a sequence's length (throws if not a sequence)
  Node at(std::size_t index) const;  // a sequence's item

  std::string as_string() const;
  double as_double() const;  // finite numbers only
  std::int64_t as_int() const;
  bool as_bool() const;
  std::vector<double> as_doubles() const;  // a sequence of finite numbers

  // Optional scalars with a default.
  double get(std::string_view key, double fallback) const;
  std::int64_t get(std::string_view key, std::int64_t fallback) const;
  int get(std::string_view key, int fallback) const;
  bool get(std::string_view key, bool fallback) const;
  std::string get(std::string_view key, const std::string& fallback) const;
  std::string get(std::string_view key, const char* fallback) const {
    return get(key, std::string(fallback));
  }

  // A mapping's keys in file order (empty for anything else).
  std::vector<std::string> keys() const;

  // Strict configuration (docs/architecture.md, rule 7): throws ConfigError for the first key of
  // this mapping that is not in `known`, at the key's own line and with the closest known key:
  // "hand.yaml:12: unknown key 'slip_tresh' in 'controller' (did you mean 'slip_thresh'?)".
  void refuse_unknown_keys(const std::vector<std::string>& known) const;
  // For data files meant to cross versions (calibrations): the same findings as one warning
  // each, "... ignored", instead of an error.
  std::vector<std::string> unknown_key_warnings(const std::vector<std::string>& known) const;

  // Throws ConfigError "<file>:<line>: key '<path>': <what>".
  [[noreturn]] void fail(const std::string& what) const;
  // The node's scalar text for messages ("<map>", "<sequence>" otherwise).
  std::string text() const;

 private:
  YAML::Node node_;
  std::string path_;
  std::shared_ptr<const std::string> source_;
};

// Parses YAML text; `source` names it in errors (usually the file name).
Node parse_yaml(const std::string& text, const std::string& source);
Node load_yaml_file(const std::filesystem::path& path);

}  // namespace tactile::config
