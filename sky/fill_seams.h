#pragma once

// Seams of a fill: an image region filled with texture copied from elsewhere (a shift map) keeps
// that texture's level, and where the sky's gradient differs between the source and the hole its
// edges show as steps: the TSI's shadow band came back a paler strip with straight edges across the
// aureole, the arm a stripe beside a cut-off cloud (looked at: sky import of the ARM day at 512 px).
//
// remove_fill_seams re-levels the fill with a Poisson solve (Perez, Gangnet & Blake 2003,
// "Poisson image editing"): inside the region the result keeps the fill's own differences between
// neighbouring pixels (its texture) and meets the known pixels around it with no step (guidance 0
// across the region's edge), in the least-squares sense. Each connected part of the region is
// solved with the known pixels at its edge; pixels outside the region are not changed.

#include <opencv2/core.hpp>

namespace dynsky {

// image: CV_32FC1 or CV_32FC3 (any colour space where differences mean something, e.g. CIELAB);
// region: CV_8UC1 of the same size, non-zero where the image was filled. Every part of the region
// must touch a pixel outside it (else there is no level to meet: an Error). Channels are solved
// with one factorisation (Eigen's sparse Cholesky).
void remove_fill_seams(cv::Mat* image, const cv::Mat& region);

}  // namespace dynsky
