#pragma once
// Which COLMAP matcher suits a set of photos (sfm.matcher auto). Sequential matching pairs each photo with its
// neighbours in name order, right for video frames and for a camera's counter (IMG_0412, IMG_0413, ...), wrong for
// an unordered collection (photos from several people, renamed or shuffled files), which it leaves mostly
// unregistered. Exhaustive matching pairs every two photos (n^2 / 2 pairs: the cost grows fast); matching by
// image retrieval (a vocabulary tree built from the photos themselves) pairs each photo with the ones that look
// most alike, whatever their order.

#include <optional>
#include <string>
#include <vector>

#include "base/enum_names.h"

namespace p2n {

// sfm.matcher: auto chooses one of the others (AutoMatcher).
enum class Matcher { kAuto, kExhaustive, kSequential, kVocabTree };
template <>
struct EnumNames<Matcher> {
  static constexpr std::pair<Matcher, const char*> kValues[] = {{Matcher::kAuto, "auto"},
                                                                {Matcher::kExhaustive, "exhaustive"},
                                                                {Matcher::kSequential, "sequential"},
                                                                {Matcher::kVocabTree, "vocab_tree"}};
};

// Whether the names read as one numbered sequence: (nearly) all end in a number after one common prefix, and the
// numbers, sorted, step by about the same amount (frames 1, 2, 3 or 5, 10, 15; a camera's counter): the median
// step at most twice the commonest, so that frames left out of a video (fox: 0001 0002 0003 0004 0006 ... 0115)
// still read as a sequence.
bool LooksLikeFrameSequence(const std::vector<std::string>& names);

// Up to this many unordered photos, exhaustive matching finds every pair for little: ours (feature_matching.h) takes
// about 11 ms per pair and core at fox's 2,668 features with VNNI (its 1,225 pairs: 6.9 s on 2 cores; 30 ms with a
// float product), COLMAP's verification about 6 ms. Retrieval's pairs (20 neighbours a photo, retrieval.h) cost as
// much each, after a vocabulary tree built and queried, and miss some; COLMAP's own matcher, which matched them
// until then, took about 250 ms a pair (fox's 536 sequential pairs: 66 s). Mapping n^2 / 2 pairs is measured up to
// 64 photos only, hence the margin. Beyond, exhaustive grows with the square of the photos and retrieval linearly.
inline constexpr int kRetrievalMinImages = 100;

// The frames of one video are matched exhaustively up to this many times `exhaustive_max_images`: a frame carries
// fewer features than a photo (a video's 720 or 1080 lines against a photo's 3000 or more), so a pair costs less, and
// sequential pairs alone leave a walk's far ends unconstrained (docs/benchmarks.md, videos).
inline constexpr int kVideoExhaustiveFactor = 2;

// sfm.matcher auto: exhaustive up to `exhaustive_max_images` photos (or kVideoExhaustiveFactor times as many frames
// of one video, `one_video`: ingest chose them, at uneven steps); above, sequential for one video's frames and for a
// numbered sequence, and for other names exhaustive up to kRetrievalMinImages and vocab_tree (retrieval) beyond.
Matcher AutoMatcher(const std::vector<std::string>& names, int exhaustive_max_images, bool one_video = false);

// The matcher to add when `first` registered too few photos: one that does not assume their order (exhaustive up
// to kRetrievalMinImages, else retrieval) after sequential, sequential after retrieval; none after exhaustive,
// whose pairs contain every other matcher's.
std::optional<Matcher> RetryMatcher(Matcher first, size_t photos);

}  // namespace p2n
