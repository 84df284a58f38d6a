#pragma once

// The page's own files (tools/tactile_web/page), compiled into the program by CMake
// (page_assets.cpp.in), so that a built tactile_web needs nothing of the source tree.
#include <string_view>

namespace tactile::web::page {

extern const std::string_view kIndexHtml;
extern const std::string_view kAppJs;
extern const std::string_view kStyleCss;

}  // namespace tactile::web::page
