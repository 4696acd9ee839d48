#pragma once
// Ingest's path for a video: its frames measured, chosen (frame_choice.h), decoded again and written to images/ as
// JPEG files named after the video and the frame (clip_00042.jpg), so that a video's frames sort in their order.

#include <OpenImageIO/imagebuf.h>

#include <filesystem>
#include <optional>
#include <vector>

#include "stages/stage_reports.h"

namespace p2n {

struct VideoIngest {
  IngestedVideo video;
  std::vector<IngestedImage> images;  // one a taken frame, in the video's order
};

// What ingest records of any decoded image, a photo's or a frame's (its fingerprint, its size and the size it is
// written at), and the image downsized to `max_image_size` (0 keeps the size).
OIIO::ImageBuf DownsizeAndDescribe(const OIIO::ImageBuf& decoded, int max_image_size, IngestedImage* out);

// `frames`: how many to take (nothing: AutoFrameCount); `max_image_size`: as for photos (0 keeps the size).
// UserError naming the file when it is not a video that can be decoded whole (video_io.h).
VideoIngest IngestVideo(const std::filesystem::path& file, const std::filesystem::path& images_dir,
                        std::optional<int> frames, int max_image_size);

}  // namespace p2n
