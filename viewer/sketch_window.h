// The sketch window of `hashfusion model --interactive`: Kellner's tool loop (click the vertices of a polygon on a
// shot, see its guidance colour at once) over photogrammetry/sketch_session.h, whose events it sends.
//
// The shown shot fills the window, scaled to fit 1280 x 800 with its aspect kept, under the session's overlay
// (the polygons in their guidance colour, the open outline white). A left click is a vertex at the image pixel
// under the cursor (window_to_image); keys send sketch_key_event's events; the title bar shows the shot, the
// current polygon's state and placement, and why the last event was refused. Returns when the window is closed or
// q / Esc is pressed. Throws hf::Error when there is no display (gl_context.h). This header includes no GL.
#pragma once

#include <optional>
#include <string>

#include "photogrammetry/sketch_session.h"

namespace hf::viewer {

void run_sketch_window(photogrammetry::SketchSession& session);

// The session event of a key (GLFW key code and modifier bits), or nullopt for keys that send none:
// Enter "close", Backspace "undo", n "new", p "same_plane", Tab "shot NEXT" and Shift-Tab "shot PREVIOUS" (the
// shots in the network's order, wrapping round).
std::optional<std::string> sketch_key_event(int key, int mods, const photogrammetry::Network& network,
                                            int shown_shot);

// The image pixel under a cursor at window coordinates (x, y) (origin top-left, in framebuffer pixels) when the
// image is drawn from the window's top-left corner scaled by `scale`: pixel centres at integers, as SKETCH.json's.
Eigen::Vector2d window_to_image(double x, double y, double scale);

}  // namespace hf::viewer
