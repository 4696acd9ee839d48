#pragma once
// Foreground masks of the photos (as Brush, Postshot and NeRD's datasets take them): a folder masks/ in a dataset or
// photo folder, one mask a photo, white on the subject and black on what to leave out. A mask becomes its photo's
// alpha, so the field, the splats and the mesh keep the subject alone.

#include <OpenImageIO/imagebuf.h>

#include <filesystem>
#include <string>
#include <vector>

namespace p2n {

// The folder of the masks of the photos in `folder` (a photo folder, or a dataset's): its masks/, or the masks/
// beside it when it is an images/ folder (a dataset's layout); empty when there is none.
std::filesystem::path MasksFolder(const std::filesystem::path& folder);

// The mask of each photo in `masks` (in the photos' order). A photo IMG_1.JPG takes the mask of the same name
// with any image extension, or with .png added (COLMAP's IMG_1.JPG.png), or with _mask (IMG_1_mask.png).
// UserError naming the folder and the photos without one, or two masks that claim one photo.
std::vector<std::filesystem::path> MatchMasks(const std::filesystem::path& masks,
                                              const std::vector<std::filesystem::path>& photos);

// `mask`'s first channel at `width` x `height` (the size of `photo`, decoded upright), one float channel in [0, 1].
// A mask of the photo's stored sides where its EXIF `orientation` turned it a quarter (5 to 8) is turned as it was;
// one of another size but the same shape is resized. Near-black and near-white values snap to 0 and 1, so that JPEG
// noise does not leave a faint veil. UserError naming both files when the shapes differ.
OIIO::ImageBuf ReadMask(const std::filesystem::path& mask, const std::filesystem::path& photo, int width, int height,
                        int orientation = 1);

// `image` (decoded from `photo`) with `mask` (ReadMask) as its alpha, multiplied into an alpha it has.
OIIO::ImageBuf WithMask(const OIIO::ImageBuf& image, const std::filesystem::path& photo,
                        const std::filesystem::path& mask);

}  // namespace p2n
