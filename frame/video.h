// What an animation folder is summed up by: MP4s of its numbered PNGs (ffmpeg, Debian's) and a
// contact sheet of evenly spaced frames.
#pragma once

#include <string>

#include "frame/frame_store.h"

namespace dynsky {

// PREFIX_0000.png .. PREFIX_(frames - 1).png of the folder at `fps` to `out` (H.264, yuv420p, even size), through a temporary
// name renamed when complete (util/atomic_file.h). Throws dynsky::Error naming out, leaving no
// partial file, if ffmpeg is missing, fails, writes nothing or writes an incomplete MP4 (its boxes
// do not tile the file, or the index is missing: ffmpeg exits 0 when the trailer's write fails).
void make_video(const std::string& folder, const std::string& prefix, int frames, double fps, const std::string& out,
                bool quiet);

// Up to 12 frames, evenly spaced from the first to the last, each 320 pixels wide, in a full grid
// (no empty cells: up to 5 frames in one row; more in rows of 4, 3 or 5, whichever shows the most,
// the count rounded down to fill them), each labelled with its frame time t = k / fps.
void make_contact_sheet(const FrameStore& store, int total, double fps, const std::string& out);

// How many frames the contact sheet of an animation of `total` frames shows, in how many columns.
void contact_sheet_grid(int total, int* count, int* columns);

// A frame's time as the contact sheet labels it: "12.5 s", "14 min 24 s", "4 h", "1 h 05 min 30 s"
// (printf's %g gave "1.44e+04 s" on a day-long animation).
std::string frame_time_label(double seconds);

}  // namespace dynsky
