#include "base/image_io.h"

#include <OpenImageIO/hash.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <vector>

#include "base/format.h"

namespace p2n {
namespace {

int OpenCvDepth(OIIO::TypeDesc type) {
  if (type == OIIO::TypeDesc::UINT8) return CV_8U;
  if (type == OIIO::TypeDesc::UINT16) return CV_16U;
  return CV_32F;
}

// OpenEXR (3.1) allocates an attribute's declared size before reading it: a 217-byte file that declares a
// 1.9 GB attribute took 2 GB of memory and 7 s to be refused (found by image_fuzz). This walks the header's
// attributes (name, type, 32-bit size, value) and refuses one that declares more bytes than the file has.
// Returns the error, or an empty string for a file that is not an EXR or whose header is consistent.
std::string CheckExrHeader(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char start[8];
  if (!in.read(start, 8) || std::memcmp(start, "\x76\x2f\x31\x01", 4) != 0) return "";
  const bool multipart = (static_cast<unsigned char>(start[5]) & 0x10) != 0;
  std::error_code error;
  const uint64_t file_size = std::filesystem::file_size(path, error);
  while (true) {  // one header, or for multi-part files one per part and then an empty one
    int attributes = 0;
    std::string name, type;
    while (std::getline(in, name, '\0') && !name.empty()) {
      int32_t size = 0;
      if (!std::getline(in, type, '\0') || !in.read(reinterpret_cast<char*>(&size), 4)) break;
      const uint64_t at = static_cast<uint64_t>(in.tellg());
      if (size < 0 || at + static_cast<uint64_t>(size) > file_size) {
        return "damaged EXR header: attribute '" + name.substr(0, 64) + "' declares " + std::to_string(size) +
               " bytes in a file of " + std::to_string(file_size);
      }
      in.seekg(size, std::ios::cur);
      ++attributes;
    }
    if (!in) return "damaged EXR header: the file ends inside it";
    if (!multipart || attributes == 0) return "";
  }
}

// libpng (1.6, as Debian builds it) also allocates a chunk's declared length before reading it: a 320-byte PNG
// whose tEXt chunk declares 1.9 GB took 2 GB of memory to be refused (found by image_fuzz). This walks the
// chunks (32-bit big-endian length, type, data, CRC) up to IEND and refuses one whose data would run past the
// end of the file. Returns the error, or an empty string for a file that is not a PNG or whose chunks fit.
std::string CheckPngChunks(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char signature[8];
  if (!in.read(signature, 8) || std::memcmp(signature, "\x89PNG\r\n\x1a\n", 8) != 0) return "";
  std::error_code error;
  const uint64_t file_size = std::filesystem::file_size(path, error);
  unsigned char header[8];
  while (in.read(reinterpret_cast<char*>(header), 8)) {
    const uint64_t length =
        uint64_t{header[0]} << 24 | uint64_t{header[1]} << 16 | uint64_t{header[2]} << 8 | header[3];
    std::string type(reinterpret_cast<const char*>(header + 4), 4);
    for (char& c : type) c = std::isalpha(static_cast<unsigned char>(c)) ? c : '?';
    if (static_cast<uint64_t>(in.tellg()) + length > file_size) {
      return "damaged PNG: chunk '" + type + "' declares " + std::to_string(length) + " bytes in a file of " +
             std::to_string(file_size);
    }
    if (type == "IEND") break;
    in.seekg(static_cast<std::streamoff>(length + 4), std::ios::cur);  // the data and the CRC
  }
  return "";
}

}  // namespace

std::string CameraIdentity(const OIIO::ImageSpec& spec) {
  std::vector<std::string> parts;
  for (const char* key : {"Make", "Model", "Exif:LensModel"}) {
    const std::string value = OIIO::Strutil::strip(spec.get_string_attribute(key));
    if (!value.empty()) parts.push_back(value);
  }
  const float focal = spec.get_float_attribute("Exif:FocalLength", 0.0f);
  if (focal > 0) parts.push_back(format("{:.3g} mm", focal));
  return OIIO::Strutil::join(parts, ", ");
}

ReadImageResult ReadImage(const std::filesystem::path& path) {
  ReadImageResult result;
  std::error_code error;
  if (std::filesystem::file_size(path, error) == 0 && !error) {
    result.error = "empty file (0 bytes)";
    return result;
  }
  result.error = CheckExrHeader(path);
  if (result.ok()) result.error = CheckPngChunks(path);
  if (!result.ok()) return result;
  // Straight (unassociated) alpha, as the file stores it: a transparent pixel keeps its colour.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto input = OIIO::ImageInput::open(path.string(), &config);
  if (!input) {
    result.error = "not a readable image: " + OIIO::geterror();
    return result;
  }
  OIIO::ImageSpec spec = input->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) {
    result.error = "the image has no pixels";
    return result;
  }
  if (spec.width > kMaxImageSide || spec.height > kMaxImageSide ||
      int64_t{spec.width} * spec.height > kMaxImagePixels || spec.nchannels > 16) {
    result.error = "declared size " + std::to_string(spec.width) + "x" + std::to_string(spec.height) + "x" +
                   std::to_string(spec.nchannels) + " is beyond what photo2nerf reads";
    return result;
  }
  // Keep 8- and 16-bit integers; everything else (half, float, 32-bit ints) becomes float.
  if (spec.format != OIIO::TypeDesc::UINT8 && spec.format != OIIO::TypeDesc::UINT16) {
    spec.format = OIIO::TypeDesc::FLOAT;
  }
  spec.x = spec.y = spec.z = 0;
  spec.full_x = spec.full_y = spec.full_z = 0;
  spec.full_width = spec.width;
  spec.full_height = spec.height;
  OIIO::ImageBuf image(spec, OIIO::InitializePixels::No);
  const bool read_ok = input->read_image(0, 0, 0, spec.nchannels, spec.format, image.localpixels());
  const std::string decoder_message = input->geterror();
  if (!read_ok || !decoder_message.empty()) {
    result.error =
        "cannot decode: " + (decoder_message.empty() ? std::string("unknown decoder error") : decoder_message);
    return result;
  }
  result.orientation = spec.get_int_attribute("Orientation", 1);
  result.camera = CameraIdentity(spec);
  for (const char* key : {"jpeg:ColorSpace", "tiff:ColorSpace"}) {
    const std::string space = spec.get_string_attribute(key);
    result.from_cmyk |= space == "CMYK" || space == "YCCK";
  }
  if (result.orientation != 1) {
    result.image = OIIO::ImageBufAlgo::reorient(image);
    if (result.image.has_error()) {
      result.error = "cannot apply EXIF orientation: " + result.image.geterror();
      return result;
    }
  } else {
    result.image = std::move(image);
  }
  return result;
}

OIIO::ImageBuf DownsizeToFit(const OIIO::ImageBuf& image, int max_side) {
  const OIIO::ImageSpec& spec = image.spec();
  const int longest = std::max(spec.width, spec.height);
  if (max_side <= 0 || longest <= max_side) return image;
  const double scale = static_cast<double>(max_side) / longest;
  const int width = std::max(1, static_cast<int>(std::lround(spec.width * scale)));
  const int height = std::max(1, static_cast<int>(std::lround(spec.height * scale)));
  const int depth = OpenCvDepth(spec.format);
  const cv::Mat source(spec.height, spec.width, CV_MAKETYPE(depth, spec.nchannels),
                       const_cast<void*>(image.localpixels()));
  OIIO::ImageSpec out_spec(width, height, spec.nchannels, spec.format);
  out_spec.channelnames = spec.channelnames;
  out_spec.alpha_channel = spec.alpha_channel;
  OIIO::ImageBuf out(out_spec, OIIO::InitializePixels::No);
  cv::Mat target(height, width, CV_MAKETYPE(depth, spec.nchannels), out.localpixels());
  cv::resize(source, target, target.size(), 0, 0, cv::INTER_AREA);
  return out;
}

std::string PixelFingerprint(const OIIO::ImageBuf& image) {
  const OIIO::ImageSpec& spec = image.spec();
  const std::string layout = std::to_string(spec.width) + "x" + std::to_string(spec.height) + "x" +
                             std::to_string(spec.nchannels) + ":" + spec.format.c_str();
  OIIO::SHA1 sha1;
  sha1.append(layout.data(), layout.size());
  sha1.append(image.localpixels(), spec.image_bytes());
  return sha1.digest();
}

ImageFileHeader ReadImageHeader(const std::filesystem::path& path, std::string* error) {
  auto input = OIIO::ImageInput::open(path.string());
  if (!input) {
    *error = OIIO::geterror();
    return {};
  }
  const OIIO::ImageSpec& spec = input->spec();
  return {spec.width, spec.height, spec.nchannels, spec.get_int_attribute("Orientation", 1)};
}

std::string WriteImage(const OIIO::ImageBuf& image, const std::filesystem::path& path) {
  auto output = OIIO::ImageOutput::create(path.string());
  if (!output) return "cannot write '" + path.string() + "': " + OIIO::geterror();
  OIIO::ImageSpec spec = image.spec();
  spec.attribute("png:compressionLevel", 3);  // fast: ingest writes many large PNGs
  if (!output->open(path.string(), spec) || !output->write_image(spec.format, image.localpixels()) ||
      !output->close()) {
    return "cannot write '" + path.string() + "': " + output->geterror();
  }
  return "";
}

}  // namespace p2n
