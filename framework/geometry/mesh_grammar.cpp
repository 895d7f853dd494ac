// The mesh formats' grammar, checked before Assimp (geometry/mesh_grammar_impl.h).

#include "geometry/mesh_grammar_impl.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string_view>
#include <unordered_map>
#include <vector>

#include <fmt/format.h>

#include "core/error.h"

namespace spec2fab {

void mesh_file_error(const std::filesystem::path& file, const std::string& verb,
                     const std::string& reason) {
  throw InputError(file.string() + ": cannot " + verb + " mesh: " + reason);
}

namespace {

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& verb,
                       const std::string& reason) {
  mesh_file_error(file, verb, reason);
}

}  // namespace

namespace {

/// A line quoted in a message: at most 60 characters, bytes outside
/// printable ASCII as '?' (the user's terminal gets one clean line).
std::string shown_line(const std::string& line) {
  std::string shown = line.substr(0, 60);
  for (char& c : shown)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return shown + (line.size() > 60 ? "..." : "");
}

int ply_type_size(const std::string& type) {
  static const std::unordered_map<std::string, int> sizes = {
      {"char", 1},  {"uchar", 1},   {"int8", 1},   {"uint8", 1},  {"short", 2}, {"ushort", 2},
      {"int16", 2}, {"uint16", 2},  {"int", 4},    {"uint", 4},   {"int32", 4}, {"uint32", 4},
      {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto found = sizes.find(type);
  return found == sizes.end() ? 0 : found->second;
}

}  // namespace

/// A text format's bytes from `offset` on: tabs, line ends and printable
/// characters only. Assimp's text readers take a NUL for the end of the
/// buffer, and its PLY reader a header line ended by another control byte
/// for no end at all: both have crashed it (fuzz_mesh).
void check_text(const std::filesystem::path& file, const char* format, std::uintmax_t offset) {
  std::ifstream in(file, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(offset));
  std::vector<char> chunk(1 << 16);
  for (std::uintmax_t at = offset; in;) {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    const auto got = static_cast<size_t>(in.gcount());
    for (size_t i = 0; i < got; ++i) {
      const auto c = static_cast<unsigned char>(chunk[i]);
      if (c < 32 && c != '\t' && c != '\n' && c != '\r')
        fail(file, "read",
             fmt::format("byte {} is a control character (0x{:02x}), and {} is text", at + i, c,
                         format));
    }
    at += got;
  }
}

namespace {

/// An ASCII PLY body against its header: one line per element (LF or CRLF
/// ends it; a lone CR is refused, as Assimp would start a new line there
/// and read the rest against the wrong element), each scalar property a
/// number, each list a count its type can hold and that many numbers
/// (Assimp allocates what a list count says before it reads), nothing
/// more on the line, and a face's vertex indices within the vertex count.
template <class Element>
void check_ply_ascii_body(const std::filesystem::path& file, std::istream& in,
                          const std::vector<Element>& elements) {
  check_text(file, "an ASCII PLY file", static_cast<std::uintmax_t>(in.tellg()));
  const auto is_number = [](const std::string& word) {
    char* end = nullptr;
    std::strtod(word.c_str(), &end);
    return !word.empty() && end == word.c_str() + word.size();
  };
  double vertices = 0;
  for (const Element& element : elements)
    if (element.name == "vertex") vertices = element.count;
  size_t e = 0;
  double held = 0;  // lines of elements[e] so far
  const auto skip_full = [&] {
    while (e < elements.size() && held >= elements[e].count) ++e, held = 0;
  };
  skip_full();
  for (std::string row; e < elements.size() && std::getline(in, row);) {
    if (!row.empty() && row.back() == '\r') row.pop_back();
    if (row.find_first_not_of(" \t") == std::string::npos) continue;
    const Element& element = elements[e];
    const auto bad = [&](const std::string& what) {
      fail(file, "read", fmt::format("malformed PLY: {} element {}: {}", element.name, held, what));
    };
    if (row.find('\r') != std::string::npos)
      bad("a carriage return inside the line (PLY lines end with LF or CRLF)");
    std::istringstream words(row);
    std::string word;
    for (const auto& property : element.properties) {
      if (!(words >> word) || !is_number(word)) bad("a property is missing or not a number");
      if (property.list_most < 0) continue;
      const double count = std::strtod(word.c_str(), nullptr);
      if (count < 0 || count > property.list_most || count != std::floor(count))
        bad(fmt::format("a list count of {}, where its type holds whole numbers up to {:.0f}", word,
                        property.list_most));
      for (double k = 0; k < count; ++k) {
        if (!(words >> word) || !is_number(word))
          bad(fmt::format("the list says {:.0f} items and holds fewer", count));
        if (!property.vertex_indices) continue;
        const double index = std::strtod(word.c_str(), nullptr);
        if (index < 0 || index >= vertices || index != std::floor(index))
          bad(fmt::format("vertex index {}, where the file has {:.0f} vertices (0 to {:.0f})",
                          word.substr(0, 24), vertices, vertices - 1));
      }
    }
    if (words >> word)
      bad(fmt::format("more values than its {} propert{}", element.properties.size(),
                      element.properties.size() == 1 ? "y" : "ies"));
    ++held;
    skip_full();
  }
  if (e < elements.size())
    fail(file, "read",
         fmt::format("the PLY header says {:.0f} {} elements, the file holds {:.0f}",
                     elements[e].count, elements[e].name, held));
}

}  // namespace

namespace {

/// A PLY header as it is read, line by line: the format, each element's
/// name, count (an ASCII file holds one line each) and properties, and the
/// bytes the elements need at least (each element its scalar properties'
/// bytes, or two characters in ASCII).
class PlyHeader {
 public:
  struct Property {
    double list_most = -1;        // -1 for a scalar, a list's largest count for a list
    bool vertex_indices = false;  // a face's list of vertex indices
  };
  struct Element {
    std::string name;
    double count;
    std::vector<Property> properties;
  };

  explicit PlyHeader(const std::filesystem::path& file) : file_(file) {}

  [[noreturn]] void bad(int number, const std::string& what) const {
    fail(file_, "read", "malformed PLY header, line " + std::to_string(number) + ": " + what);
  }

  enum class Line { comment, declaration, end_header };
  /// Reads line `number`.
  Line read_line(int number, std::string line) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    for (const char c : line)
      if (static_cast<unsigned char>(c) < 32 && c != '\t')
        bad(number,
            fmt::format("a control character (0x{:02x}); words are separated by spaces or tabs",
                        static_cast<unsigned char>(c)));
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "comment" || keyword == "obj_info" || keyword.empty()) return Line::comment;
    for (const char c : line)
      if (static_cast<unsigned char>(c) > 126)
        bad(number, "a byte outside ASCII in '" + keyword + "' line");
    if (keyword == "format")
      format_line(number, words);
    else if (keyword == "element")
      element_line(number, words, line);
    else if (keyword == "property")
      property_line(number, words, line);
    else if (keyword == "end_header")
      return Line::end_header;
    else
      bad(number, "unknown keyword '" + keyword + "'");
    return Line::declaration;
  }

  /// At end_header (line `number`, `left` bytes after it): the counts fit,
  /// and there are vertices and faces.
  void end(int number, double left) {
    close_element();
    if (needed_bytes_ > left)
      fail(file_, "read",
           "the PLY header declares elements that need at least " +
               std::to_string(static_cast<long long>(needed_bytes_)) + " bytes, and the file has " +
               std::to_string(static_cast<long long>(left)) + " after it (truncated?)");
    const auto named = [&](const char* name) {
      return std::any_of(elements_.begin(), elements_.end(),
                         [&](const Element& e) { return e.name == name; });
    };
    if (!named("vertex")) bad(number, "no vertex element before end_header");
    if (!named("face") && !named("tristrips")) bad(number, "no face element before end_header");
  }

  bool ascii() const { return format_ == "ascii"; }
  const std::vector<Element>& elements() const { return elements_; }

 private:
  void format_line(int number, std::istringstream& words) {
    if (!format_.empty()) bad(number, "a second format line");
    std::string version;
    words >> format_ >> version;
    if (format_ != "ascii" && format_ != "binary_little_endian" && format_ != "binary_big_endian")
      bad(number, "unknown format '" + format_ + "'");
    if (version != "1.0") bad(number, "version '" + version + "', where PLY has only 1.0");
  }

  void element_line(int number, std::istringstream& words, const std::string& line) {
    std::string name, count;
    words >> name >> count;
    if (format_.empty()) bad(number, "an element before the format line");
    if (name.empty() || count.empty() ||
        count.find_first_not_of("0123456789") != std::string::npos || count.size() > 12)
      bad(number, "'element' needs a name and a count, got '" + line + "'");
    close_element();
    element_count_ = std::stod(count);
    element_bytes_ = 0;
    elements_.push_back({name, element_count_, {}});
  }

  void property_line(int number, std::istringstream& words, const std::string& line) {
    if (element_count_ < 0) bad(number, "a property before any element");
    std::string type;
    words >> type;
    if (type == "list") {
      std::string count_type, item_type, name;
      words >> count_type >> item_type >> name;
      if (ply_type_size(count_type) == 0 || ply_type_size(item_type) == 0 || name.empty())
        bad(number,
            "'property list' needs a count type, an item type and a name, got '" + line + "'");
      element_bytes_ += ply_type_size(count_type);
      const int count_size = ply_type_size(count_type);
      elements_.back().properties.push_back(
          {count_size >= 4 ? 2147483647.0 : std::pow(2.0, 8 * count_size) - 1,
           elements_.back().name == "face" &&
               (name == "vertex_indices" || name == "vertex_index")});
    } else {
      std::string name;
      words >> name;
      if (ply_type_size(type) == 0 || name.empty())
        bad(number, "'property' needs a type and a name, got '" + line + "'");
      element_bytes_ += ply_type_size(type);
      elements_.back().properties.push_back({});
    }
  }

  void close_element() {
    if (element_count_ >= 0)
      needed_bytes_ += element_count_ * (ascii() ? 2.0 : std::max(element_bytes_, 1.0));
  }

  std::filesystem::path file_;
  std::string format_;
  double needed_bytes_ = 0;  // at least, for the elements declared
  double element_count_ = -1, element_bytes_ = 0;
  std::vector<Element> elements_;
};

}  // namespace

/// Assimp's PLY reader loops forever on some malformed headers and trusts
/// element counts when it allocates, so a PLY file's header is read first:
/// its grammar, and counts that the bytes after it can hold.
void check_ply_header(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string line;
  if (!std::getline(in, line) || line.rfind("ply", 0) != 0)
    return;  // not a PLY file: its reader decides
  const std::uintmax_t size = std::filesystem::file_size(file);
  PlyHeader header(file);
  for (int number = 2; std::getline(in, line); ++number) {
    const PlyHeader::Line read = header.read_line(number, line);
    if (read == PlyHeader::Line::end_header) {
      header.end(number, static_cast<double>(size) - static_cast<double>(in.tellg()));
      if (header.ascii()) check_ply_ascii_body(file, in, header.elements());
      return;
    }
    if (read == PlyHeader::Line::declaration && number > 10000) header.bad(number, "no end_header");
  }
  fail(file, "read", "malformed PLY header: no end_header");
}

std::string lowercase_extension(const std::filesystem::path& file) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

/// An ASCII OFF file's grammar, before Assimp (which reports a short face
/// list as its own validation failure): the counts, each vertex's three
/// coordinates, each face's corner count (at least 3) and its corners.
/// Read line by line; comments (#) and blank lines are skipped.
void check_off(const std::filesystem::path& file) {
  if (lowercase_extension(file) != ".off") return;
  std::string text;
  {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    text = std::move(bytes).str();
  }
  const auto bad = [&](const std::string& what) { fail(file, "read", "malformed OFF: " + what); };
  // The header as Assimp 5.2.5's OFF reader walks it (NextToken: blanks,
  // line ends and whole comment lines between tokens), so that the body
  // below starts where its starts; then lines as its GetNextLine cuts them
  // (at CR or LF, runs of line ends taken as one). Its vertex loop reads one
  // line per vertex and its face loop one per face, skipping a line it
  // cannot take as a face while counting the faces down: enough such lines
  // wrap the count below zero, and every later pass over the faces reads
  // far past them (SIGSEGV, found by fuzz_mesh: lines ended by lone CRs,
  // which a check that cut lines at LF alone took for one). Here every
  // vertex line must hold three numbers and the next lines a face each,
  // so that the reader skips none.
  const size_t size = text.size();
  const auto line_end = [](char c) { return c == '\r' || c == '\n'; };
  const auto blank = [](char c) { return c == ' ' || c == '\t'; };
  size_t at = 0;
  const auto next_token = [&] {
    while (at < size && (blank(text[at]) || line_end(text[at]))) ++at;
    while (at < size && text[at] == '#') {
      while (at < size && !line_end(text[at])) ++at;
      while (at < size && (blank(text[at]) || line_end(text[at]))) ++at;
    }
  };
  const auto word_here = [&] {
    size_t end_of_word = at;
    while (end_of_word < size && !blank(text[end_of_word]) && !line_end(text[end_of_word])) ++end_of_word;
    return text.substr(at, end_of_word - at);
  };
  next_token();
  if (at == size) bad("the file is empty");
  const std::string keyword = word_here();
  if (keyword.size() < 3 || keyword.compare(keyword.size() - 3, 3, "OFF") != 0)
    bad(fmt::format("the first word is '{}', not OFF", shown_line(keyword)));
  {
    size_t line_stop = at;
    while (line_stop < size && !line_end(text[line_stop])) ++line_stop;
    if (text.substr(at, line_stop - at).find("BINARY") != std::string::npos) return;  // binary OFF: its reader decides
  }
  {
    // The prefixes Assimp reads, in its order: ST (texture coordinates), C
    // (colours), N (normals), 4 (homogeneous). An n (a dimension before the
    // counts) would move the counts, so it is refused.
    std::string_view rest(keyword);
    for (const std::string_view prefix : {"ST", "C", "N", "4"})
      if (rest.substr(0, prefix.size()) == prefix) rest.remove_prefix(prefix.size());
    if (rest != "OFF")
      bad(fmt::format("'{}' is not read here (OFF, with ST, C, N or 4 before it)", shown_line(keyword)));  // not "'" + …: g++ 12 warns falsely (-Wrestrict)
  }
  check_text(file, "an OFF file");
  at += keyword.size();
  next_token();
  // Three counts (vertices, faces, edges): plain digits, as strtoul10 reads them.
  long long counts[3] = {-1, -1, -1};
  for (long long& count : counts) {
    next_token();
    const std::string word = word_here();
    if (word.empty() || word.size() > 9 || !std::all_of(word.begin(), word.end(), [](char c) { return c >= '0' && c <= '9'; }))
      bad("no vertex and face counts after the OFF line");
    count = std::stoll(word);
    at += word.size();
  }
  next_token();
  const long long vertices = counts[0], faces = counts[1];
  // The body's lines.
  const auto next_line = [&](std::string& line) {
    if (at >= size) return false;
    const size_t begin = at;
    while (at < size && !line_end(text[at])) ++at;
    line.assign(text, begin, at - begin);
    while (at < size && line_end(text[at])) ++at;
    return true;
  };
  // Assimp copies a line into 4096 bytes and writes its end one past them.
  const auto check_length = [&](const std::string& line, const char* what, long long index) {
    if (line.size() >= 4096)
      bad(fmt::format("{} {}'s line is {} characters long (at most 4095)", what, index, line.size()));
  };
  std::string row;
  for (long long v = 0; v < vertices; ++v) {
    if (!next_line(row)) bad(fmt::format("the header says {} vertices, the file holds {}", vertices, v));
    check_length(row, "vertex", v);
    std::istringstream coordinates(row);
    double x, y, z;
    if (!(coordinates >> x >> y >> z))
      bad(fmt::format("vertex {} has not three coordinates: '{}'", v, shown_line(row)));
  }
  for (long long f = 0; f < faces; ++f) {
    if (!next_line(row)) bad(fmt::format("the header says {} faces, the file holds {}", faces, f));
    check_length(row, "face", f);
    std::istringstream corners(row);
    long long count = -1;
    corners >> count;
    if (!corners || count < 3)
      bad(fmt::format("face {} has {} corners: '{}'", f, std::max(count, 0LL), shown_line(row)));
    if (count > 9)
      bad(fmt::format("face {} has {} corners; the OFF reader takes at most 9 (split the polygon)", f, count));
    for (long long k = 0; k < count; ++k) {
      long long index = -1;
      if (!(corners >> index))
        bad(fmt::format("face {} says {} corners and lists fewer: '{}'", f, count, shown_line(row)));
      if (index < 0 || index >= vertices)
        bad(fmt::format("face {} refers to vertex {}, and there are {}", f, index, vertices));
    }
  }
}

/// A binary STL's triangle count against its size, before Assimp (which,
/// when the 80-byte header starts with "solid", takes the file for ASCII
/// and reports "no vertices"): 84 + 50 bytes per triangle.
void check_binary_stl(const std::filesystem::path& file) {
  if (lowercase_extension(file) != ".stl") return;
  const std::uintmax_t size = std::filesystem::file_size(file);
  std::ifstream in(file, std::ios::binary);
  std::string start(4096, '\0');  // the header, and enough to tell text from binary
  in.read(start.data(), static_cast<std::streamsize>(start.size()));
  start.resize(static_cast<size_t>(in.gcount()));
  // ASCII: "solid" then text only (no control bytes) in its first 4 kB.
  const bool text = std::all_of(start.begin(), start.end(), [](char c) {
    return static_cast<unsigned char>(c) >= 32 || c == '\n' || c == '\r' || c == '\t';
  });
  if (start.rfind("solid", 0) == 0 && text) return check_text(file, "an ASCII STL file");
  if (start.size() < 84)
    fail(file, "read",
         fmt::format("a binary STL has an 84-byte header; the file has {} bytes", size));
  std::uint32_t triangles = 0;
  std::memcpy(&triangles, start.data() + 80,
              sizeof triangles);  // little-endian, as the format and this machine are
  const double needed = 84.0 + 50.0 * triangles;
  if (static_cast<double>(size) < needed)
    fail(
        file, "read",
        fmt::format("the binary STL header says {} triangles ({:.0f} bytes), the file has {} bytes "
                    "(truncated, or not an STL)",
                    triangles, needed, size));
}


namespace {

/// One vertex reference of an OBJ statement, strictly: v, v/vt, v//vn or
/// v/vt/vn, each index a nonzero integer of at most 9 digits without a
/// leading zero or a sign other than '-'. Assimp's face reader steps over a
/// reference by its value's digit count, so "01" or "+1" would count as two.
bool is_vertex_reference(std::string_view token) {
  int part = 0;
  for (size_t at = 0; at <= token.size(); ++part) {
    const size_t slash = std::min(token.find('/', at), token.size());
    std::string_view index = token.substr(at, slash - at);
    const bool may_be_empty = part == 1 && slash < token.size();  // v//vn
    if (part > 2) return false;
    if (index.empty()) {
      if (!may_be_empty) return false;
    } else {
      if (index.front() == '-') index.remove_prefix(1);
      if (index.empty() || index.size() > 9 || index.front() < '1' || index.front() > '9' ||
          !std::all_of(index.begin(), index.end(), [](char c) { return c >= '0' && c <= '9'; }))
        return false;
    }
    at = slash + 1;
  }
  return true;
}

/// An OBJ statement of vertex references, which Assimp's face reader takes
/// any line starting with 'f', 'l' or 'p' for (its keyword is skipped
/// whatever it is): strict references only (Assimp 5.2.5 reads a number
/// past the line's end where atoi overflows), at least as many as the kind
/// needs. With normals and no texture coordinates before it, Assimp reads
/// v/vt/vn's middle index as the normal and gives up on the rest of the
/// line at the third, so such a reference is refused too: the line would
/// count fewer vertices than it lists.
void check_obj_elements(const std::filesystem::path& file, const std::string& line, long long number,
                        bool texture_coordinates_seen, bool normals_seen) {
  const char kind = line.front();
  const int needed = kind == 'f' ? 3 : kind == 'l' ? 2 : 1;
  const char* const what = kind == 'f' ? "a face" : kind == 'l' ? "a line statement" : "a point statement";
  const auto blank = [](char c) { return c == ' ' || c == '\t'; };
  int references = 0;
  size_t at = 0;
  while (at < line.size() && !blank(line[at])) ++at;  // the keyword
  while (true) {
    while (at < line.size() && blank(line[at])) ++at;
    if (at == line.size()) break;
    const size_t begin = at;
    while (at < line.size() && !blank(line[at])) ++at;
    const std::string_view token(line.data() + begin, at - begin);
    if (!is_vertex_reference(token))
      fail(file, "read",
           fmt::format("malformed OBJ, line {}: '{}' is not a vertex reference, in '{}'", number,
                       shown_line(std::string(token)), shown_line(line)));
    const size_t slash = token.find('/'), second = token.find('/', slash + 1);
    if (normals_seen && !texture_coordinates_seen && second != std::string_view::npos && second > slash + 1)
      fail(file, "read",
           fmt::format("malformed OBJ, line {}: '{}' names a texture coordinate, and the file has normals but no "
                       "texture coordinates before it (write v//vn)",
                       number, shown_line(std::string(token))));
    ++references;
  }
  if (references < needed)
    fail(file, "read",
         fmt::format("malformed OBJ, line {}: {} needs {} or more vertices, '{}' has {}", number, what,
                     needed == 3 ? "three" : needed == 2 ? "two" : "one", shown_line(line), references));
}

/// The first word of a line (up to a blank).
std::string_view first_word(const std::string& line) {
  return std::string_view(line).substr(0, std::min(line.find_first_of(" \t"), line.size()));
}

}  // namespace

/// An OBJ file's text, and its statements of vertex references (faces,
/// lines, points). Debian 12's Assimp (5.2.5) gives a line statement of one
/// vertex no room in its mesh and still writes it: a later line then writes
/// past the mesh's arrays, corrupting the heap (found by fuzz_mesh; fixed
/// upstream in 5.3.0). The file is read as Assimp reads it: lines end at CR
/// or LF; a line's first byte says what it is; a free-form section
/// (`cstype` to `end`) is skipped; a line continued by a backslash is
/// refused, since Assimp joins such lines unlike the format says (it takes
/// the byte after the line end as it comes, and reads past its buffer when
/// the backslash ends one of its 16 MiB blocks).
void check_obj(const std::filesystem::path& file) {
  if (lowercase_extension(file) != ".obj") return;
  check_text(file, "an OBJ file");
  std::ifstream in(file, std::ios::binary);
  std::streambuf& bytes = *in.rdbuf();  // byte by byte, without istream's per-call checks
  constexpr int kEnd = std::char_traits<char>::eof();
  std::string line;
  long long number = 1;
  bool free_form = false, texture_coordinates = false, normals = false;
  const auto end_line = [&] {
    if (line.empty()) return;
    const char kind = line.front();
    if (free_form) {
      free_form = !(kind == 'e' && first_word(line) == "end");
    } else if (kind == 'c') {
      free_form = first_word(line) == "cstype";
    } else if (kind == 'v' && line.size() > 1) {
      texture_coordinates = texture_coordinates || line[1] == 't';
      normals = normals || line[1] == 'n';
    } else if (kind == 'f' || kind == 'l' || kind == 'p') {
      check_obj_elements(file, line, number, texture_coordinates, normals);
    }
    line.clear();
  };
  constexpr std::uint64_t kAssimpBlock = std::uint64_t{1} << 24;  // IOStreamBuffer's cache
  std::uint64_t offset = 0;
  for (int c = bytes.sbumpc(); c != kEnd; c = bytes.sbumpc(), ++offset) {
    if (c == '\\' && (bytes.sgetc() == '\r' || bytes.sgetc() == '\n'))
      fail(file, "read",
           fmt::format("malformed OBJ, line {}: a line continued by a backslash (join it with the next)", number));
    if (c == '\\' && offset % kAssimpBlock == kAssimpBlock - 1)  // Assimp would look at the byte past its block
      fail(file, "read", fmt::format("malformed OBJ, line {}: a backslash at byte {}", number, offset));
    if (c == '\r' || c == '\n') {
      end_line();
      if (c == '\n' || bytes.sgetc() != '\n') ++number;  // LF, CRLF or a lone CR
      continue;
    }
    // Only the statements checked above are kept whole.
    if (line.empty() || line.front() == 'f' || line.front() == 'l' || line.front() == 'p' ||
        line.size() < 8)
      line.push_back(static_cast<char>(c));
  }
  end_line();
}

}  // namespace spec2fab
