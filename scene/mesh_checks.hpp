// Checks of mesh files before assimp reads them, for the formats whose assimp readers trust what
// a file says about itself.
//
// OFF (Object File Format: "OFF", counts, vertex lines, face lines). Assimp's OFF reader trusts the
// header: counts larger than the data leave faces with no indices (an assertion inside assimp then
// aborts the process), an index past the vertices is clamped to the last one, a face of more than 9
// vertices is dropped, and a line of 4096 characters or more overflows its line buffer. This check
// reads the file the way that reader does and rejects each of those.
#pragma once

#include <string_view>

namespace scatter {

// Throws std::runtime_error saying what is wrong and on which line.
void check_off_text(std::string_view text);

// PLY: the header ("ply", "format", "element NAME COUNT", "property TYPE NAME",
// "property list TYPE TYPE NAME", "comment", "obj_info", "end_header"). Assimp's PLY reader loops
// without end on some malformed headers and allocates what the counts say before it reads the data.
// This checks the header's grammar and that the data holds what the header counts: in ascii, one
// line per row with a number per property (a length, then that many, per list); in binary, every
// row, its lists' lengths read as the file's byte order says, inside the data.
void check_ply(std::string_view bytes);

// GLB (binary glTF: a 12-byte header "glTF", version, length, then chunks of a 4-byte length, a
// 4-byte type and the data; version 1: a 20-byte header whose content length and format follow).
// Assimp's readers allocate what a length says, plus one, before they read it (a JSON chunk of
// 0xfffffff9 bytes asked for 4 GiB). This checks the header, and that the stated length and every
// chunk lie inside the file.
void check_glb(std::string_view bytes);

// STL: binary (an 80-byte header, a 32-bit facet count, 50 bytes a facet) or text ("solid ...").
// Assimp reads a file as binary when 84 + 50 x count equals its size in 32-bit arithmetic, checks
// the size the same way, then allocates three vertices a facet: a count of 85899346 in an 88-byte
// file wraps to 88 and asks for 3 GiB. This rejects a count whose true size is not the file's.
void check_stl(std::string_view bytes);

}  // namespace scatter
