// PNG output of the figures (see figure_png.h).
#include "figure_png.h"

#include "upd/io/atomic_file.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <stdexcept>
#include <vector>

namespace upd::nav {

void writePngAtomically(const mrpt::img::CImage& image, const std::string& path) {
  // CImage keeps an OpenCV matrix in the order cv::imwrite expects (as CImage::saveToFile does).
  const cv::Mat mat = image.asCvMat<cv::Mat>(mrpt::img::SHALLOW_COPY);
  std::vector<unsigned char> bytes;
  if (!cv::imencode(".png", mat, bytes)) throw std::runtime_error(path + ": cannot encode the PNG");
  io::writeFileAtomically(path, [&](std::ostream& os) {
    os.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  });
}

}  // namespace upd::nav
