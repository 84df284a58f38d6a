// The two CSV files of the calibration workflow (docs/calibration.md, "Calibration workflow"):
// samples (applied loads against measured G and u) and loads (which frame had which load).
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <map>
#include <stdexcept>

#include "calibrate.hpp"
#include "tactile/util/files.hpp"

namespace tactile::calibrate {
namespace {

std::string trim(std::string_view s) {
  std::size_t b = 0;
  std::size_t e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t' || s[b] == '\r'))
    ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t' || s[e - 1] == '\r'))
    --e;
  return std::string(s.substr(b, e - b));
}

// One line into fields: commas separate, a field in double quotes may hold commas ("" is a
// quote), spaces around fields are dropped.
std::vector<std::string> split(std::string_view line, const std::string& where) {
  std::vector<std::string> out;
  std::string field;
  bool quoted = false;
  bool was_quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"' && trim(field).empty()) {
      quoted = true;
      was_quoted = true;
      field.clear();
    } else if (c == ',') {
      out.push_back(was_quoted ? field : trim(field));
      field.clear();
      was_quoted = false;
    } else {
      field += c;
    }
  }
  if (quoted) throw std::runtime_error(where + ": a quoted field is not closed");
  out.push_back(was_quoted ? field : trim(field));
  return out;
}

// A table: a header row, then rows; '#' starts a comment line, blank lines are skipped.
struct Table {
  std::map<std::string, std::size_t> columns;
  struct Row {
    std::vector<std::string> fields;
    std::size_t line = 0;
  };
  std::vector<Row> rows;
};

Table parse_table(const std::string& text, const std::string& source) {
  Table t;
  bool have_header = false;
  std::size_t line_no = 0;
  std::size_t pos = 0;
  std::size_t header_size = 0;
  while (pos <= text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    const std::string stripped = trim(line);
    if (stripped.empty() || stripped[0] == '#') continue;
    const std::string where = source + ":" + std::to_string(line_no);
    auto fields = split(line, where);
    if (!have_header) {
      for (std::size_t i = 0; i < fields.size(); ++i) {
        if (fields[i].empty()) throw std::runtime_error(where + ": the header has an empty name");
        if (!t.columns.emplace(fields[i], i).second)
          throw std::runtime_error(where + ": column '" + fields[i] + "' appears twice");
      }
      header_size = fields.size();
      have_header = true;
      continue;
    }
    if (fields.size() != header_size) {
      throw std::runtime_error(
          fmt::format("{}: {} fields, the header has {}", where, fields.size(), header_size));
    }
    t.rows.push_back({std::move(fields), line_no});
  }
  if (!have_header) throw std::runtime_error(source + ": no header line (the file is empty)");
  return t;
}

class RowReader {
 public:
  RowReader(const Table& t, const Table::Row& r, const std::string& source)
      : t_(t), r_(r), where_(source + ":" + std::to_string(r.line)) {}
  const std::string& where() const { return where_; }

  // The cell, or nullopt when the column is absent or the cell empty.
  std::optional<std::string> text(const char* column) const {
    const auto it = t_.columns.find(column);
    if (it == t_.columns.end() || r_.fields[it->second].empty()) return std::nullopt;
    return r_.fields[it->second];
  }
  std::optional<double> number(const char* column) const {
    const auto s = text(column);
    if (!s) return std::nullopt;
    double v = 0;
    const auto [end, ec] = std::from_chars(s->data(), s->data() + s->size(), v);
    if (ec != std::errc() || end != s->data() + s->size() || !std::isfinite(v)) {
      throw std::runtime_error(where_ + ": column '" + column + "' must be a finite number, is '" +
                               *s + "'");
    }
    return v;
  }
  double required(const char* column) const {
    const auto v = number(column);
    if (!v) throw std::runtime_error(where_ + ": column '" + column + "' is empty");
    return *v;
  }
  std::uint32_t element() const {
    const auto s = text("element");
    if (!s) throw std::runtime_error(where_ + ": column 'element' is empty");
    std::uint64_t v = 0;
    const auto [end, ec] = std::from_chars(s->data(), s->data() + s->size(), v);
    if (ec != std::errc() || end != s->data() + s->size() || v > UINT32_MAX) {
      throw std::runtime_error(where_ + ": column 'element' must be an element id (0.." +
                               std::to_string(UINT32_MAX) + "), is '" + *s + "'");
    }
    return static_cast<std::uint32_t>(v);
  }
  void fail(const std::string& what) const { throw std::runtime_error(where_ + ": " + what); }

 private:
  const Table& t_;
  const Table::Row& r_;
  std::string where_;
};

void require_columns(const Table& t, const std::string& source,
                     std::initializer_list<const char*> names) {
  for (const char* n : names) {
    if (!t.columns.contains(n))
      throw std::runtime_error(source + ": the header has no column '" + n + "'");
  }
}

void require_pair(const Table& t, const std::string& source, const char* a, const char* b) {
  if (t.columns.contains(a) != t.columns.contains(b)) {
    throw std::runtime_error(source + ": columns '" + a + "' and '" + b +
                             "' go together: give both or neither");
  }
}

// One CSV field: quoted when it holds a comma, a quote or surrounding spaces.
std::string field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos && trim(s) == s) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

}  // namespace

std::vector<Sample> parse_samples(const std::string& text, const std::string& source) {
  const Table t = parse_table(text, source);
  require_columns(t, source, {"element", "fz_N", "G"});
  require_pair(t, source, "fx_N", "ux_mm");
  require_pair(t, source, "fy_N", "uy_mm");
  std::vector<Sample> out;
  out.reserve(t.rows.size());
  for (const auto& row : t.rows) {
    const RowReader r(t, row, source);
    Sample s;
    s.where = r.where();
    s.element = r.element();
    s.fz_n = r.required("fz_N");
    if (s.fz_n < 0) r.fail("column 'fz_N' must not be negative (a press), is " + *r.text("fz_N"));
    s.G = r.required("G");
    if (s.G < 0) r.fail("column 'G' must not be negative, is " + *r.text("G"));
    const auto fx = r.number("fx_N");
    const auto ux = r.number("ux_mm");
    if (fx.has_value() != ux.has_value()) r.fail("give both fx_N and ux_mm, or neither");
    if (fx) {
      s.has_x = true;
      s.fx_n = *fx;
      s.ux_mm = *ux;
    }
    const auto fy = r.number("fy_N");
    const auto uy = r.number("uy_mm");
    if (fy.has_value() != uy.has_value()) r.fail("give both fy_N and uy_mm, or neither");
    if (fy) {
      s.has_y = true;
      s.fy_n = *fy;
      s.uy_mm = *uy;
    }
    if (const auto c = r.number("contact")) {
      if (*c != 0 && *c != 1) r.fail("column 'contact' must be 0 or 1, is " + *r.text("contact"));
      s.contact = *c == 1;
    }
    s.frame = r.text("frame").value_or("");
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<Sample> read_samples(const std::filesystem::path& path) {
  return parse_samples(util::read_file(path), path.string());
}

std::string format_samples(const std::vector<Sample>& samples) {
  std::string out = "element,fz_N,G,contact,fx_N,ux_mm,fy_N,uy_mm,frame\n";
  const auto num = [](bool has, double v) { return has ? fmt::format("{}", v) : std::string(); };
  for (const Sample& s : samples) {
    out += fmt::format("{},{},{},{},{},{},{},{},{}\n", s.element, s.fz_n, s.G, s.contact ? 1 : 0,
                       num(s.has_x, s.fx_n), num(s.has_x, s.ux_mm), num(s.has_y, s.fy_n),
                       num(s.has_y, s.uy_mm), field(s.frame));
  }
  return out;
}

std::vector<LoadRow> parse_loads(const std::string& text, const std::string& source) {
  const Table t = parse_table(text, source);
  require_columns(t, source, {"frame", "element", "fz_N"});
  std::vector<LoadRow> out;
  out.reserve(t.rows.size());
  for (const auto& row : t.rows) {
    const RowReader r(t, row, source);
    LoadRow l;
    l.where = r.where();
    const auto frame = r.text("frame");
    if (!frame) r.fail("column 'frame' is empty");
    l.frame = *frame;
    l.element = r.element();
    l.fz_n = r.required("fz_N");
    if (l.fz_n < 0) r.fail("column 'fz_N' must not be negative (a press), is " + *r.text("fz_N"));
    if (const auto fx = r.number("fx_N")) {
      l.has_x = true;
      l.fx_n = *fx;
    }
    if (const auto fy = r.number("fy_N")) {
      l.has_y = true;
      l.fy_n = *fy;
    }
    out.push_back(std::move(l));
  }
  if (out.empty()) throw std::runtime_error(source + ": no rows after the header");
  return out;
}

}  // namespace tactile::calibrate
