#include "formats/npy.h"

#include <zlib.h>

#include <charconv>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>

#include "base/errors.h"
#include "base/format.h"

namespace p2n {
namespace {

constexpr size_t kMaxValues = size_t{1} << 31;  // 2^31 values: far beyond any dataset we read
constexpr uint64_t kMaxDeflateRatio = 1100;

std::string ReadAll(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UserError(format("cannot read '{}'", path.string()));
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

template <class T>
T Load(const std::string& bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}

// A name from a file, fit for a message: control and non-ASCII bytes become '?' (a NUL would cut it short).
std::string Printable(const std::string& name) {
  std::string printable = name.substr(0, 200);
  for (char& c : printable) {
    if (c < 0x20 || c > 0x7e) c = '?';
  }
  return printable;
}

[[noreturn]] void Bad(const std::string& source, const std::string& problem) {
  throw UserError(format("'{}' is not a NumPy array photo2nerf reads: {}", source, problem));
}

}  // namespace

size_t NpyArray::size() const {
  size_t n = 1;
  for (const size_t d : shape) n *= d;
  return n;
}

NpyArray ParseNpy(const std::string& bytes, const std::string& source) {
  if (bytes.size() < 10 || bytes.compare(0, 6, "\x93NUMPY") != 0) Bad(source, "no NumPy magic");
  const int major = static_cast<unsigned char>(bytes[6]);
  const size_t header_length = major == 1 ? Load<uint16_t>(bytes, 8) : Load<uint32_t>(bytes, 8);
  const size_t data_offset = (major == 1 ? 10 : 12) + header_length;
  if (major < 1 || major > 3 || data_offset > bytes.size()) Bad(source, "a damaged header");
  const std::string header = bytes.substr(major == 1 ? 10 : 12, header_length);
  std::smatch match;
  if (!std::regex_search(header, match, std::regex(R"('descr':\s*'([<|=])([fu])(\d)')"))) {
    Bad(source, "the element type is not a little-endian float or unsigned byte: " + header);
  }
  const char kind = match[2].str()[0];
  const int width = std::stoi(match[3].str());
  if (!((kind == 'f' && (width == 4 || width == 8)) || (kind == 'u' && width == 1))) {
    Bad(source, "the element type is not float32, float64 or uint8");
  }
  if (std::regex_search(header, std::regex(R"('fortran_order':\s*True)"))) Bad(source, "Fortran order");
  if (!std::regex_search(header, match, std::regex(R"('shape':\s*\(([^)]*)\))"))) Bad(source, "no shape");
  NpyArray array;
  std::stringstream dims(match[1].str());
  std::string dim;
  size_t count = 1;
  while (std::getline(dims, dim, ',')) {
    if (dim.find_first_not_of(" ") == std::string::npos) continue;
    const size_t first = dim.find_first_not_of(" ");
    size_t d = 0;
    const auto [end, error] = std::from_chars(dim.data() + first, dim.data() + dim.size(), d);
    if (error != std::errc() || dim.find_first_not_of(" L", end - dim.data()) != std::string::npos) {
      Bad(source, "a shape that is not a list of sizes: (" + match[1].str() + ")");
    }
    if (d != 0 && count > kMaxValues / d) Bad(source, "an absurd shape");
    count *= d;
    array.shape.push_back(d);
  }
  if ((bytes.size() - data_offset) / width < count) Bad(source, "fewer values than its shape says (truncated?)");
  array.values.resize(count);
  const char* data = bytes.data() + data_offset;
  for (size_t i = 0; i < count; ++i) {
    if (kind == 'u') {
      array.values[i] = static_cast<unsigned char>(data[i]);
    } else if (width == 4) {
      float v;
      std::memcpy(&v, data + 4 * i, 4);
      array.values[i] = v;
    } else {
      std::memcpy(&array.values[i], data + 8 * i, 8);
    }
  }
  return array;
}

NpyArray ReadNpy(const std::filesystem::path& path) { return ParseNpy(ReadAll(path), path.string()); }

std::map<std::string, NpyArray> ReadNpz(const std::filesystem::path& path) {
  const std::string zip = ReadAll(path);
  std::map<std::string, NpyArray> arrays;
  size_t offset = 0;
  // Walk the local file headers: signature, method, sizes, name, extra field, data.
  while (offset + 30 <= zip.size() && Load<uint32_t>(zip, offset) == 0x04034b50) {
    const uint16_t flags = Load<uint16_t>(zip, offset + 6), method = Load<uint16_t>(zip, offset + 8);
    uint64_t compressed = Load<uint32_t>(zip, offset + 18), uncompressed = Load<uint32_t>(zip, offset + 22);
    const uint16_t name_length = Load<uint16_t>(zip, offset + 26), extra_length = Load<uint16_t>(zip, offset + 28);
    if (offset + 30 + name_length + extra_length > zip.size()) Bad(path.string(), "a truncated zip entry");
    const std::string name = Printable(zip.substr(offset + 30, name_length));
    // ZIP64: the sizes are in the extra field (NumPy writes it for large arrays). Each record must fit in it.
    const size_t extra_end = offset + 30 + name_length + extra_length;
    for (size_t e = offset + 30 + name_length; e + 4 <= extra_end;) {
      const uint16_t id = Load<uint16_t>(zip, e), size = Load<uint16_t>(zip, e + 2);
      if (e + 4 + size > extra_end) Bad(path.string(), "a damaged zip extra field");
      if (id == 1 && size >= 16) {
        uncompressed = Load<uint64_t>(zip, e + 4);
        compressed = Load<uint64_t>(zip, e + 12);
      }
      e += 4 + size;
    }
    if (flags & 0x08) Bad(path.string(), "zip entries with data descriptors are not supported");
    const size_t data = offset + 30 + name_length + extra_length;
    if (compressed > zip.size() - data || uncompressed > kMaxValues * 8) Bad(path.string(), "a damaged zip entry");
    // Deflate expands at most ~1032:1; a stored entry not at all. A larger declared size is a lie: refuse it
    // before allocating.
    if ((method == 8 && uncompressed > kMaxDeflateRatio * compressed + 1024) ||
        (method == 0 && uncompressed != compressed)) {
      Bad(path.string(), format("{} declares {} bytes from {} compressed ones", name, uncompressed, compressed));
    }
    std::string bytes;
    if (method == 0) {
      bytes = zip.substr(data, compressed);
    } else if (method == 8) {
      bytes.resize(uncompressed);
      z_stream stream{};
      stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(zip.data() + data));
      stream.avail_in = static_cast<uInt>(compressed);
      stream.next_out = reinterpret_cast<Bytef*>(bytes.data());
      stream.avail_out = static_cast<uInt>(uncompressed);
      if (inflateInit2(&stream, -MAX_WBITS) != Z_OK) Bad(path.string(), "cannot start inflating");
      const int result = inflate(&stream, Z_FINISH);
      inflateEnd(&stream);
      if (result != Z_STREAM_END || stream.total_out != uncompressed) Bad(path.string(), name + " does not inflate");
    } else {
      Bad(path.string(), format("{} uses zip compression method {}", name, method));
    }
    std::string key = name;
    if (key.size() > 4 && key.compare(key.size() - 4, 4, ".npy") == 0) key.resize(key.size() - 4);
    arrays[key] = ParseNpy(bytes, path.string() + ":" + name);
    offset = data + compressed;
  }
  if (arrays.empty()) Bad(path.string(), "no arrays (is it an .npz archive?)");
  return arrays;
}

}  // namespace p2n
