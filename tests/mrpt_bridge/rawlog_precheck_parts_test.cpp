// Parts of observations stored as objects of their own (a rawlog holds none; a damaged one may
// start at one): the reader skips them, but MRPT reads them first, so their sizes are checked as
// they are inside an observation.
#include "rawlog_bytes.h"

#include <mrpt/img/CImage.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/math/CMatrixD.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/poses/CPosePDFParticles.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

namespace {

using upd::test::damageReason;
using upd::test::reasonWith;
using upd::test::serialized;
using upd::test::TempDir;
using upd::test::u32;

}  // namespace

TEST(RawlogPrecheck, PartsOfObservationsOnTheirOwnAreCheckedAsInside) {
  TempDir tmp;
  std::size_t head = 0;

  mrpt::maps::CSimplePointsMap points;
  for (int i = 0; i < 5; ++i) points.insertPoint(0.1f * i, 0.2f, 0.3f);
  const std::string map = serialized(points);
  EXPECT_EQ(damageReason(tmp, map, &head), "(read)");
  const std::size_t count_at = map.find("CSimplePointsMap") + 17;  // after the version byte
  ASSERT_EQ(map.substr(count_at, 4), u32(5));
  EXPECT_EQ(reasonWith(tmp, map, count_at, u32(0xFFFFFFF0u), &head),
            "corrupt CSimplePointsMap: point count 4294967280 at byte " +
                std::to_string(head + count_at) + " (more than 16777216 points)");

  mrpt::math::CMatrixD m(2, 3);
  m.setConstant(1.5);
  const std::string matrix = serialized(m);
  EXPECT_EQ(damageReason(tmp, matrix, &head), "(read)");
  const std::size_t rows_at = matrix.find(u32(2) + u32(3));
  ASSERT_NE(rows_at, std::string::npos);
  EXPECT_EQ(reasonWith(tmp, matrix, rows_at, u32(70000), &head),
            "corrupt CMatrixD: matrix rows 70000 at byte " + std::to_string(head + rows_at) +
                " (more than 65535 rows)");

  mrpt::poses::CPosePDFParticles particles(3);
  const std::string pdf = serialized(particles);
  EXPECT_EQ(damageReason(tmp, pdf, &head), "(read)");
  const std::size_t particles_at = pdf.find(u32(3));
  ASSERT_NE(particles_at, std::string::npos);
  EXPECT_EQ(reasonWith(tmp, pdf, particles_at, u32(200000000), &head),
            "corrupt CPosePDFParticles: particle count 200000000 at byte " +
                std::to_string(head + particles_at) + " (more than 100000 particles)");

  const bool jpeg_off = mrpt::img::CImage::DISABLE_JPEG_COMPRESSION();
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(false);
  mrpt::img::CImage picture(32, 24, mrpt::img::CH_RGB);
  picture.filledRectangle(0, 0, 31, 23, mrpt::img::TColor(40, 120, 200));
  const std::string image = serialized(picture);
  mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(jpeg_off);
  EXPECT_EQ(damageReason(tmp, image, &head), "(read)");
  const std::size_t jpeg_at = image.find("\xFF\xD8\xFF");
  ASSERT_NE(jpeg_at, std::string::npos);
  EXPECT_EQ(reasonWith(tmp, image, jpeg_at - 4, u32(0xFFFFFFF0u), &head),
            "corrupt CImage: image JPEG size 4294967280 at byte " +
                std::to_string(head + jpeg_at - 4) + " (more than 268435456 bytes)");

  EXPECT_EQ(damageReason(tmp, serialized(mrpt::poses::CPose3D(1, 2, 3, 0.1, 0.2, 0.3)), &head),
            "(read)");
}
