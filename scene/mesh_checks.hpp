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

// GLB (binary glTF 2.0: a 12-byte header "glTF", version, length, then chunks of a 4-byte length,
// a 4-byte type and the data: the JSON, then the binary buffer) (scene/glb_checks.cpp). Assimp's
// readers allocate what a length says, plus one, before they read it (a JSON chunk of 0xfffffff9
// bytes asked for 4 GiB); its glTF 1.0 reader reads accessors and buffer views unchecked (an
// assertion aborts the process); its glTF 2.0 reader takes a sparse accessor without a buffer view
// as count x element size bytes of zeros (4 GiB for a 544-byte file) and one without indices as a
// null pointer, and parses the JSON recursively. This takes version 2 only and checks the header,
// that every chunk lies inside the file on 4-byte boundaries, and then the JSON: nested at most
// kMaxGlbDepth deep; every buffer inside the binary chunk or its data URI, every buffer view
// inside its buffer, every accessor dense and inside its view, every index that names one of them
// in range.
void check_glb(std::string_view bytes);

// STL: binary (an 80-byte header, a 32-bit facet count, 50 bytes a facet) or text ("solid ...").
// Assimp takes a file as binary when 84 + 50 x count equals its size in 32-bit arithmetic, so a
// count of 85899346 in an 88-byte file (2^32 + 88) is read as binary; Debian's assimp 5.2.5 then
// checks the size in 64 bits and refuses it ("file is too small to hold all facets"), but a
// reader that checked it the 32-bit way would allocate 3 vertices a facet (3 GiB). This rejects
// a count whose true size is not the file's, naming both, whatever the assimp.
void check_stl(std::string_view bytes);

}  // namespace scatter
