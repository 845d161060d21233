// `pointbake report CAMPAIGN_DIR [--out DIR] [--viewpoints N] [--thumbnail-px N]
// [--crop-px N]`: (re)writes the report of a finished campaign folder
// (report.h), e.g. with more viewpoints or smaller images for a document,
// without running anything.
#pragma once

#include "cli/cli.h"

namespace pb {

// Exit 0 on success, 2 on bad input or usage (errors on stderr).
CliCommand ReportCommand();

}  // namespace pb
