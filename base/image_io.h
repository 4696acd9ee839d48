#pragma once
// Strict image reading and writing (OpenImageIO): a file is either a whole, upright image or an error that
// says why. Used by ingest and by everything that loads photos.

#include <OpenImageIO/imagebuf.h>

#include <filesystem>
#include <string>

namespace p2n {

// Declared sizes above these are refused before any pixel memory is allocated.
inline constexpr int kMaxImageSide = 32768;
inline constexpr int64_t kMaxImagePixels = int64_t{256} << 20;

struct ReadImageResult {
  OIIO::ImageBuf image;    // upright (EXIF orientation applied), in the file's pixel type, straight alpha
  int orientation = 1;     // the EXIF orientation that was applied (1: none)
  bool from_cmyk = false;  // the file stores CMYK (or YCCK) that the decoder turned into RGB
  std::string camera;      // CameraIdentity of its EXIF
  std::string error;       // empty on success; otherwise why the file is not a usable image
  bool ok() const { return error.empty(); }
};

// The camera an image's EXIF names: make, model, lens and focal length ("Apple iPhone 12, iPhone 12 back camera
// 4.2mm f/1.6, 4.2 mm"), empty when it names none of them.
std::string CameraIdentity(const OIIO::ImageSpec& spec);

// Decodes the whole file. Any decoder complaint (a truncated JPEG decodes partly and only warns) is an error.
ReadImageResult ReadImage(const std::filesystem::path& path);

// What a file's header declares.
struct ImageFileHeader {
  int width = 0, height = 0, channels = 0;  // as stored
  int orientation = 1;                      // EXIF's (5 to 8: ReadImage swaps width and height)
};
// The file's header only; all 0 with `error` set when it cannot be read.
ImageFileHeader ReadImageHeader(const std::filesystem::path& path, std::string* error);

// Downsizes so that the longer side is at most `max_side` with an area filter; smaller images are returned as
// they are. Float and half images are resized in float.
OIIO::ImageBuf DownsizeToFit(const OIIO::ImageBuf& image, int max_side);

// SHA-1 of the decoded pixels and their layout: changes when one pixel changes, not when the file is touched or
// re-encoded losslessly.
std::string PixelFingerprint(const OIIO::ImageBuf& image);

// Writes the image (format from the extension); returns the error or an empty string.
std::string WriteImage(const OIIO::ImageBuf& image, const std::filesystem::path& path);

}  // namespace p2n
