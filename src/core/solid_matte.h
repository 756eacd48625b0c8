#pragma once
// Solid subjects from soft background-removal masks. A salient-object network (ISNet, U^2-Net) often
// gives a pale body inside a confident outline a middling alpha (the white body of a bag on a light
// background comes out half transparent), although the subject is opaque there. solid_matte makes the
// subject opaque inside its outline and keeps what the network drew at its edges and in its holes:
//  - the core is where the alpha is at least kSolidMatteCore; the regions of the rest that reach the image
//    border without crossing the core are the outside; the regions the core encloses are inside;
//  - a clear region inside the subject (alpha at most kSolidMatteClear) of at least kSolidMatteMinHole of
//    the subject's area (the core and the regions it encloses) is a hole and stays open: a ring's hole.
//    Smaller clear regions are closed: the networks miss pale patches of a pale subject on a pale
//    background (the white scales of a crocodile-leather bag, in the colour of the wall behind it), and
//    neither their alpha nor their colour tells them from the background seen through a hole;
//  - the other pixels of the subject become opaque, except near the open ones (the outside, the holes): at a
//    distance d from the nearest open pixel the alpha is raised to at least clamp(d / r - 1, 0, 1), so
//    within the edge radius r the network's soft edge stays as drawn, and beyond 2 r all is opaque.
// The edge radius is one pixel per 256 of the image's larger side (at least one): the networks see the
// photo at 320 or 1024 px and draw edges a few of their pixels wide. The alpha is only ever raised.
#include "core/image.h"

namespace u3d {

inline constexpr float kSolidMatteCore = 0.5f;
inline constexpr float kSolidMatteClear = 0.1f;
inline constexpr double kSolidMatteMinHole = 0.01;

// alpha: 1 channel in [0, 1]. Returns the solid alpha, 1 channel, the same size.
Image solid_matte(const Image& alpha);

}  // namespace u3d
