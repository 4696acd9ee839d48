#pragma once
// String formatting for messages: the {fmt} library, as OpenImageIO ships it.

#include <OpenImageIO/strutil.h>

namespace p2n {
using OIIO::Strutil::fmt::format;
}  // namespace p2n
