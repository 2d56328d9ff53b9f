// The observations of a rawlog, walked as MRPT 2.5.8's serializeFrom() reads them (the versions it
// writes, and the older ones whose layout differs only in the fields named here), with every size
// MRPT allocates from checked before MRPT reads it.
#include "rawlog_precheck_cursor.h"

#include <csetjmp>
#include <cstdio>  // before jpeglib.h, which uses FILE and size_t without including them
#include <vector>

#include <jpeglib.h>

#include <mrpt/obs/CObservationIMU.h>  // COUNT_IMU_DATA_FIELDS

namespace upd::mrpt_bridge::detail {
namespace {

constexpr Parse kRead = Parse::Read;
constexpr Parse kOther = Parse::OtherLayout;
constexpr Parse kImpossible = Parse::Impossible;

// An object header of one of the classes named; false for any other.
bool header(Cursor& c, ObjectHeader& h, std::initializer_list<const char*> classes) {
  if (!readHeader(c, h)) return false;
  for (const char* name : classes) {
    if (h.class_name == name) return true;
  }
  return false;
}

bool endOf(Cursor& c, const ObjectHeader& h) { return !h.has_end_flag || c.endFlag(); }

// A std::string: a 32-bit length, then the bytes (MRPT resizes the string to the length first).
Parse string(Cursor& c, const char* field, std::string& why,
             std::uint32_t max_bytes = kMaxStringBytes) {
  const std::uint64_t at = c.position();
  std::uint32_t length = 0;
  if (!c.value(length)) return kOther;
  if (!withinBound(field, length, at, max_bytes, "bytes", why)) return kImpossible;
  c.skip(length);
  return kRead;
}

// Rows and columns of an image or matrix, each read as 32 bits.
Parse sides(Cursor& c, const char* field, std::uint64_t& rows, std::uint64_t& cols,
            std::string& why) {
  const std::uint64_t at = c.position();
  std::uint32_t r = 0, k = 0;
  if (!c.value(r) || !c.value(k)) return kOther;
  const std::string name(field);
  if (!withinBound((name + " rows").c_str(), r, at, kMaxImageSide, "rows", why) ||
      !withinBound((name + " columns").c_str(), k, at + 4, kMaxImageSide, "columns", why) ||
      !withinBound((name + " pixels").c_str(), std::uint64_t{r} * k, at, kMaxImagePixels, "pixels",
                   why)) {
    return kImpossible;
  }
  rows = r;
  cols = k;
  return kRead;
}

// CMatrix, CMatrixF, CMatrixD (version 0): rows, columns, then the elements.
Parse matrix(Cursor& c, const char* field, std::string& why) {
  ObjectHeader h;
  if (!header(c, h, {"CMatrix", "CMatrixF", "CMatrixD"}) || h.version != 0) return kOther;
  std::uint64_t rows = 0, cols = 0;
  const Parse p = sides(c, field, rows, cols, why);
  if (p != kRead) return p;
  c.skip(rows * cols * (h.class_name == "CMatrixD" ? sizeof(double) : sizeof(float)));
  return endOf(c, h) ? kRead : kOther;
}

// CPose3D (version 0-1: a homogeneous matrix object, 2: x y z and a quaternion, 3: x y z and a
// rotation matrix), CPose3DQuat (0), CPose2D (0: floats, 1: doubles).
Parse pose(Cursor& c, std::string& why) {
  ObjectHeader h;
  if (!header(c, h, {"CPose3D", "CPose3DQuat", "CPose2D"})) return kOther;
  const int v = h.version;
  if (h.class_name == "CPose3D" && v <= 1) {
    const Parse p = matrix(c, "pose matrix", why);
    if (p != kRead) return p;
  } else if (h.class_name == "CPose3D" && (v == 2 || v == 3)) {
    c.skip((v == 2 ? 7 : 12) * sizeof(double));
  } else if (h.class_name == "CPose3DQuat" && v == 0) {
    c.skip(7 * sizeof(double));
  } else if (h.class_name == "CPose2D" && (v == 0 || v == 1)) {
    c.skip(3 * (v == 0 ? sizeof(float) : sizeof(double)));
  } else {
    return kOther;
  }
  return endOf(c, h) ? kRead : kOther;
}

// TCamera, versions 0-6: the focal length and 5 distortion parameters (3 more from version 3), the
// intrinsics (a CMatrixD object before version 4, 4 doubles from it), a CMatrixD of distortion
// (version 0), the resolution (from 2), the camera's name (from 5), the distortion model (6: a
// byte). MRPT reallocates each CMatrixD to the size it reads before it checks it is 3 x 3 or 1 x 5.
Parse camera(Cursor& c, std::string& why) {
  ObjectHeader h;
  if (!header(c, h, {"TCamera"}) || h.version > 6) return kOther;
  const int v = h.version;
  c.skip((v >= 3 ? 9 : 6) * sizeof(double));
  Parse p = kRead;
  if (v < 4) {
    p = matrix(c, "camera intrinsics", why);
  } else {
    c.skip(4 * sizeof(double));
  }
  if (p == kRead && v == 0) p = matrix(c, "camera distortion", why);
  if (p != kRead) return p;
  if (v >= 2) c.skip(2 * sizeof(std::uint32_t));
  if (v >= 5 && (p = string(c, "camera name length", why)) != kRead) return p;
  if (v >= 6) c.skip(1);
  return endOf(c, h) ? kRead : kOther;
}

// MRPT decodes a CImage's JPEG with libjpeg and its default error handler, which ends the process
// (exit) on a fatal error in the data, and allocates the image the JPEG's header states. The same
// bytes go through the same calls of the same libjpeg here first (read the header, decompress every
// line, finish: the end markers too), with a handler that returns instead.
struct JpegFailure {
  jpeg_error_mgr mgr;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

[[noreturn]] void jpegErrorExit(j_common_ptr info) {
  auto* failure = reinterpret_cast<JpegFailure*>(info->err);
  info->err->format_message(info, failure->message);
  std::longjmp(failure->jump, 1);
}

void jpegQuiet(j_common_ptr) {}  // warnings (a missing end marker): MRPT reads on

// "" when the JPEG decodes; else why. Only plain data crosses the setjmp.
std::string jpegFailure(const std::uint8_t* data, std::size_t size, std::uint64_t* pixels) {
  jpeg_decompress_struct info;
  JpegFailure failure;
  info.err = jpeg_std_error(&failure.mgr);
  failure.mgr.error_exit = jpegErrorExit;
  failure.mgr.output_message = jpegQuiet;
  failure.message[0] = '\0';
  JSAMPARRAY row = nullptr;
  if (setjmp(failure.jump) != 0) {
    jpeg_destroy_decompress(&info);
    return failure.message;
  }
  jpeg_create_decompress(&info);
  jpeg_mem_src(&info, data, static_cast<unsigned long>(size));
  jpeg_read_header(&info, TRUE);
  *pixels = std::uint64_t{info.image_width} * info.image_height;
  if (*pixels > kMaxImagePixels) {
    jpeg_destroy_decompress(&info);
    return "too large";
  }
  jpeg_start_decompress(&info);
  row = (*info.mem->alloc_sarray)(reinterpret_cast<j_common_ptr>(&info), JPOOL_IMAGE,
                                  info.output_width * info.output_components, 1);
  while (info.output_scanline < info.output_height) jpeg_read_scanlines(&info, row, 1);
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return "";
}

// A CImage with colour (version 1-9): a JPEG of its byte count, or (version 8 on) raw RGB pixels of
// the negated width and height.
Parse colourImage(Cursor& c, int version, std::string& why) {
  std::int32_t width = 1, height = 1;
  const std::uint64_t at = c.position();
  if (version >= 7 && (!c.value(width) || !c.value(height))) return kOther;
  if (width >= 1 && height >= 1) {
    const std::uint64_t bytes_at = c.position();
    std::uint32_t bytes = 0;
    if (!c.value(bytes)) return kOther;
    // MRPT allocates and zeroes a buffer of the byte count (4 GiB for 2^32 - 1) and reads into it.
    if (!withinBound("image JPEG size", bytes, bytes_at, kMaxEncodedImageBytes, "bytes", why)) {
      return kImpossible;
    }
    // MRPT hands libjpeg exactly that buffer (its source then ends the data with an EOI marker):
    // the same bytes are decoded here, not one more (a JPEG whose Huffman table runs past its byte
    // count decodes with zeros after it, but ends the process at its end).
    if (bytes == 0) return kRead;  // nothing to decode: MRPT's reader does not end the process
    // (Whether the stream holds them is asked first: a byte count far past the end of a file is
    // not allocated.)
    if (!c.has(bytes)) {
      // MRPT reads what there is without a complaint (a short read is no error to CArchive)
      // and decodes it: a JPEG cut in its header ends the process in libjpeg.
      why = "image JPEG of " + std::to_string(bytes) + " bytes at byte " +
            std::to_string(bytes_at + 4) +
            " is cut short by the end of the stream (MRPT would decode the part there is; its "
            "JPEG reader ends the process on a cut header)";
      return kImpossible;
    }
    std::vector<std::uint8_t> jpeg(bytes);
    c.bytes(jpeg.data(), bytes);  // (there, as has() found)
    std::uint64_t pixels = 0;
    const std::string failure = jpegFailure(jpeg.data(), jpeg.size(), &pixels);
    if (pixels > kMaxImagePixels) {
      why = "image JPEG at byte " + std::to_string(bytes_at + 4) + ": its header says " +
            std::to_string(pixels) + " pixels (more than " + std::to_string(kMaxImagePixels) + ")";
      return kImpossible;
    }
    if (!failure.empty()) {
      why = "image JPEG of " + std::to_string(bytes) + " bytes at byte " +
            std::to_string(bytes_at + 4) + " does not decode (" + failure +
            "; MRPT's JPEG reader would end the process)";
      return kImpossible;
    }
    return kRead;
  }
  if (width < 0 && height < 0) {  // raw pixels; -INT_MIN does not exist
    const std::uint64_t w = 0 - static_cast<std::int64_t>(width);
    const std::uint64_t h = 0 - static_cast<std::int64_t>(height);
    if (!withinBound("image width", w, at, kMaxImageSide, "pixels", why) ||
        !withinBound("image height", h, at + 4, kMaxImageSide, "pixels", why) ||
        !withinBound("image pixels", w * h, at, kMaxImagePixels, "pixels", why)) {
      return kImpossible;
    }
    c.skip(w * h * 3);
    return kRead;
  }
  if (width < 0 || height < 0) {  // MRPT would resize to a negative side read as unsigned
    why = "image size " + std::to_string(width) + " x " + std::to_string(height) + " at byte " +
          std::to_string(at) + " (a negative side with a positive one)";
    return kImpossible;
  }
  return kRead;  // 0 x N: nothing follows
}

// A grey CImage (version 2-9): width, height, origin, byte count[, depth], [zip flag], bytes.
Parse greyImage(Cursor& c, int version, std::string& why) {
  const std::uint64_t at = c.position();
  std::int32_t width = 0, height = 0, origin = 0, depth = 0;
  std::uint32_t bytes = 0;
  if (!c.value(width) || !c.value(height) || !c.value(origin) || !c.value(bytes)) return kOther;
  if (version >= 9 && !c.value(depth)) return kOther;
  const auto w = static_cast<std::uint32_t>(width), h = static_cast<std::uint32_t>(height);
  if (!withinBound("image width", w, at, kMaxImageSide, "pixels", why) ||
      !withinBound("image height", h, at + 4, kMaxImageSide, "pixels", why) ||
      !withinBound("image pixels", std::uint64_t{w} * h, at, kMaxImagePixels, "pixels", why)) {
    return kImpossible;
  }
  std::uint8_t zip = version == 3 || (version == 4 && bytes > 16 * 1024);
  if (version >= 5 && !c.value(zip)) return kOther;
  if (zip) return kOther;  // MRPT 2.5 refuses a zipped image itself
  // MRPT checks the byte count against the buffer it allocated (an ASSERT that throws).
  c.skip(bytes);
  return kRead;
}

// CImage, versions 0-9 and 100 (saved without OpenCV): stored externally (a file name) or embedded.
Parse image(Cursor& c, std::string& why) {
  ObjectHeader h;
  if (!header(c, h, {"CImage"})) return kOther;
  const int v = h.version;
  Parse p = kOther;
  std::uint8_t external = 0, colour = 0;
  if (v == 0) {  // width, height, channels, origin, bytes: read into the resized
                 // image
    const std::uint64_t at = c.position();
    std::uint32_t w = 0, height = 0, channels = 0, bytes = 0;
    std::uint8_t origin = 0;
    if (!c.value(w) || !c.value(height) || !c.value(channels) || !c.value(origin) ||
        !c.value(bytes)) {
      return kOther;
    }
    const std::uint64_t size = std::uint64_t{w} * height * channels;
    if (!withinBound("image width", w, at, kMaxImageSide, "pixels", why) ||
        !withinBound("image height", height, at + 4, kMaxImageSide, "pixels", why) ||
        !withinBound("image channels", channels, at + 8, 4, "channels", why) ||
        !withinBound("image byte count", bytes, at + 13, size, "bytes (width x height x channels)",
                     why)) {
      return kImpossible;
    }
    c.skip(bytes);
    p = kRead;
  } else if (v == 1) {
    p = colourImage(c, v, why);
  } else if (v == 100 || (v >= 2 && v <= 9)) {
    if ((v == 100 || v >= 6) && !c.value(external)) return kOther;
    if (external) {
      p = string(c, "image file name length", why);
    } else if (v == 100) {
      p = kRead;
    } else if (!c.value(colour)) {
      return kOther;
    } else {
      p = colour ? colourImage(c, v, why) : greyImage(c, v, why);
    }
  }
  if (p != kRead) return p;
  return endOf(c, h) ? kRead : kOther;
}

// An image flag, then the image when the flag is set.
Parse optionalImage(Cursor& c, const char* field, std::string& why) {
  std::uint8_t has = 0;
  const Parse p = checkFlag(c, field, has, why);
  if (p != kRead) return p;
  return has ? image(c, why) : kRead;
}

// CObservation2DRangeScan, versions 4-7.
Parse scan2D(Cursor& c, int version, std::string& why) {
  if (version < 4 || version > 7) return kOther;
  c.skip(sizeof(float) + 1 + sizeof(float));  // aperture, rightToLeft, maxRange
  Parse p = pose(c, why);
  if (p == kRead && version < 6) p = matrix(c, "sensor pose covariance", why);
  if (p != kRead) return p;
  const std::uint64_t at = c.position();
  std::uint32_t rays = 0;
  if (!c.value(rays)) return kOther;
  if (!withinBound("scan size", rays, at, kMaxScanRays, "rays", why)) return kImpossible;
  c.skip(std::uint64_t{rays} * (sizeof(float) + 1));              // ranges, validity
  c.skip(sizeof(float) + sizeof(std::uint64_t) + sizeof(float));  // stdError, stamp, beam
  if (version >= 5) {
    p = string(c, "sensor label length", why);
    if (p != kRead) return p;
    c.skip(sizeof(double));  // deltaPitch
  }
  std::uint8_t intensity = 0;
  if (version >= 7 && !c.value(intensity)) return kOther;
  if (intensity) c.skip(std::uint64_t{rays} * sizeof(std::int32_t));
  return kRead;
}

// CObservation3DRangeScan, versions 0-10: the 3D points, the range image and the other images.
Parse scan3DImages(Cursor& c, int version, std::string& why) {
  std::uint8_t has_points = 1, has_range = 0;
  Parse p = kRead;
  if (version > 0 && (p = checkFlag(c, "3D points", has_points, why)) != kRead) return p;
  if (has_points) {
    const std::uint64_t at = c.position();
    std::uint32_t n = 0;
    if (!c.value(n)) return kOther;
    if (!withinBound("3D point count", n, at, kMaxImagePixels, "points", why)) return kImpossible;
    c.skip(std::uint64_t{n} * (3 * sizeof(float) + (version == 0 ? 1 : 0) +
                               (version >= 8 ? 2 * sizeof(std::uint16_t) : 0)));
  }
  if (version == 0) return kRead;
  if ((p = checkFlag(c, "range image", has_range, why)) != kRead) return p;
  if (version >= 9) c.skip(sizeof(float));  // rangeUnits
  if (has_range) {
    if (version < 9) {
      if ((p = matrix(c, "range image", why)) != kRead) return p;
    } else {
      std::uint64_t rows = 0, cols = 0;
      if ((p = sides(c, "range image", rows, cols, why)) != kRead) return p;
      c.skip(rows * cols * sizeof(std::uint16_t));
    }
  }
  p = optionalImage(c, "intensity image", why);
  if (p == kRead) p = optionalImage(c, "confidence image", why);
  if (p == kRead && version >= 2) p = camera(c, why);  // depth camera
  if (p == kRead && version >= 4) p = camera(c, why);  // intensity camera
  if (p == kRead && version >= 4) p = pose(c, why);    // intensity camera's pose
  return p;
}

Parse scan3D(Cursor& c, int version, std::string& why) {
  if (version > 10) return kOther;
  c.skip(sizeof(float));  // maxRange
  Parse p = pose(c, why);
  if (p == kRead) p = scan3DImages(c, version, why);
  if (p != kRead) return p;
  c.skip(sizeof(float) + sizeof(std::uint64_t));  // stdError, timestamp
  if ((p = string(c, "sensor label length", why)) != kRead) return p;
  if (version >= 3 && (p = checkExternalFiles(c, why)) != kRead) return p;
  std::uint8_t range_is_depth = 0;
  if (version >= 5 && (p = checkFlag(c, "range is depth", range_is_depth, why)) != kRead) {
    return p;
  }
  if (version >= 6) c.skip(1);  // intensity channel
  std::uint8_t labels = 0;
  if (version >= 7 && (p = checkFlag(c, "pixel labels", labels, why)) != kRead) return p;
  if (labels && (p = checkPixelLabels(c, why)) != kRead) return p;
  if (version < 10) return kRead;
  std::uint8_t layers = 0;
  if (!c.value(layers)) return kOther;
  for (unsigned i = 0; i < layers; ++i) {
    if ((p = string(c, "range layer name length", why)) != kRead) return p;
    std::uint64_t rows = 0, cols = 0;
    if ((p = sides(c, "range layer", rows, cols, why)) != kRead) return p;
    c.skip(rows * cols * sizeof(std::uint16_t));
  }
  return kRead;
}

// CObservationImage, version 4: camera pose, camera, image, timestamp, label.
Parse monoImage(Cursor& c, int version, std::string& why) {
  if (version != 4) return kOther;
  Parse p = pose(c, why);
  if (p == kRead) p = camera(c, why);
  if (p == kRead) p = image(c, why);
  if (p != kRead) return p;
  c.skip(sizeof(std::uint64_t));
  return string(c, "sensor label length", why);
}

// CObservationStereoImages, version 6: pose, two cameras, the left image, the disparity and right
// flags and images, timestamp, the right camera's pose, label.
Parse stereoImages(Cursor& c, int version, std::string& why) {
  if (version != 6) return kOther;
  Parse p = pose(c, why);
  if (p == kRead) p = camera(c, why);
  if (p == kRead) p = camera(c, why);
  if (p == kRead) p = image(c, why);
  if (p != kRead) return p;
  std::uint8_t disparity = 0, right = 0;
  if ((p = checkFlag(c, "disparity image", disparity, why)) != kRead ||
      (p = checkFlag(c, "right image", right, why)) != kRead) {
    return p;
  }
  if (right && (p = image(c, why)) != kRead) return p;
  if (disparity && (p = image(c, why)) != kRead) return p;
  c.skip(sizeof(std::uint64_t));
  if ((p = pose(c, why)) != kRead) return p;
  return string(c, "sensor label length", why);
}

// A point count at the cursor, bounded as a 3D scan's points.
Parse pointCount(Cursor& c, const char* field, std::uint32_t& n, std::string& why) {
  const std::uint64_t at = c.position();
  if (!c.value(n)) return kOther;
  return withinBound(field, n, at, kMaxImagePixels, "points", why) ? kRead : kImpossible;
}

// A CPointsMap object (or a null one): the point count and the coordinates, in each class a
// count MRPT resizes every field to, then x, y, z as floats; CColouredPointsMap's colour
// channels after them are vectors of their own counts; CPointsMapXYZI's intensities and
// CWeightedPointsMap's weights have the point count. The map's options after the points are left
// to MRPT (OtherLayout), as is any other layout.
Parse pointsMap(Cursor& c, std::string& why) {
  ObjectHeader h;
  if (!readHeader(c, h)) return kOther;
  if (h.class_name == "nullptr") return endOf(c, h) ? kRead : kOther;
  const int v = h.version;
  const bool simple = h.class_name == "CSimplePointsMap" && v <= 10;
  const bool coloured = h.class_name == "CColouredPointsMap" && v <= 9;
  const bool xyzi = h.class_name == "CPointsMapXYZI" && v == 0;
  const bool weighted = h.class_name == "CWeightedPointsMap" && v <= 2;
  if (!simple && !coloured && !xyzi && !weighted) return kOther;
  std::uint32_t n = 0;
  Parse p = pointCount(c, "point count", n, why);
  if (p != kRead) return p;
  c.skip(std::uint64_t{n} * (xyzi || weighted ? 4 : 3) * sizeof(float));
  if (coloured) {
    for (const char* channel : {"red count", "green count", "blue count"}) {
      std::uint32_t k = 0;
      if ((p = pointCount(c, channel, k, why)) != kRead) return p;
      c.skip(std::uint64_t{k} * sizeof(float));
    }
  }
  return kOther;
}

// CObservationPointCloud, version 0: label, timestamp, sensor pose, the external storage flag,
// then a file name or the points map.
Parse pointCloud(Cursor& c, int version, std::string& why) {
  if (version != 0) return kOther;
  Parse p = string(c, "sensor label length", why);
  if (p != kRead) return p;
  c.skip(sizeof(std::uint64_t));
  if ((p = pose(c, why)) != kRead) return p;
  std::uint8_t external = 0;
  if ((p = checkFlag(c, "stored externally", external, why)) != kRead) return p;
  return external ? string(c, "external file name length", why) : pointsMap(c, why);
}

// CObservationComment, version 0: the text, then the timestamp.
Parse comment(Cursor& c, int version, std::string& why) {
  if (version != 0) return kOther;
  const Parse p = string(c, "comment length", why, kMaxCommentBytes);
  c.skip(sizeof(std::uint64_t));
  return p;
}

// CObservationRange, versions 0-3: the minimum and maximum range and the cone's aperture, a count
// of measurements (MRPT resizes its list to it), each an ID (from version 3), the sensor's pose (a
// CPose3D object) and the distance; the label (from 1) and the timestamp (from 2).
Parse ranges(Cursor& c, int version, std::string& why) {
  if (version > 3) return kOther;
  c.skip(3 * sizeof(float));
  const std::uint64_t at = c.position();
  std::uint32_t n = 0;
  if (!c.value(n)) return kOther;
  if (!withinBound("measurement count", n, at, kMaxRangeMeasurements, "measurements", why)) {
    return kImpossible;
  }
  Parse p = kRead;
  for (std::uint32_t i = 0; i < n && p == kRead; ++i) {
    if (version >= 3) c.skip(sizeof(std::uint16_t));
    p = pose(c, why);
    c.skip(sizeof(float));
  }
  if (p == kRead && version >= 1) p = string(c, "sensor label length", why);
  if (version >= 2) c.skip(sizeof(std::uint64_t));
  return p;
}

// CObservationGPS, versions 10-11: two timestamps, the label, the sensor pose, (11) whether the
// timestamp is the satellites', the message count, the messages (rawlog_precheck_gnss.cpp).
Parse gnss(Cursor& c, int version, std::string& why) {
  if (version != 10 && version != 11) return kOther;
  c.skip(2 * sizeof(std::uint64_t));
  Parse p = string(c, "sensor label length", why);
  if (p != kRead || (p = pose(c, why)) != kRead) return p;
  std::uint8_t satellite_time = 0;
  if (version == 11 && (p = checkFlag(c, "satellite timestamp", satellite_time, why)) != kRead) {
    return p;
  }
  const std::uint64_t at = c.position();
  std::uint32_t n = 0;
  if (!c.value(n)) return kOther;
  if (!withinBound("message count", n, at, kMaxGnssMessages, "messages", why)) return kImpossible;
  return checkGnssMessages(c, n, why);
}

// CObservationIMU, version 4: the sensor pose, a flag for each of MRPT's IMU fields, the
// timestamp, a double for each field, the label.
Parse imu(Cursor& c, int version, std::string& why) {
  if (version != 4) return kOther;
  const Parse p = pose(c, why);
  if (p != kRead) return p;
  c.skip(mrpt::obs::COUNT_IMU_DATA_FIELDS * (1 + sizeof(double)) + sizeof(std::uint64_t));
  return string(c, "sensor label length", why);
}

// CObservationOdometry, versions 0-2: the odometry (a CPose2D object), label, timestamp; from
// version 1 the encoder ticks (always in version 1, after their flag in 2) and the velocities
// (two floats in version 1, a TTwist2D after their flag in 2).
Parse odometry(Cursor& c, int version, std::string& why) {
  if (version > 2) return kOther;
  Parse p = pose(c, why);
  if (p != kRead || (p = string(c, "sensor label length", why)) != kRead) return p;
  c.skip(sizeof(std::uint64_t));
  if (version == 0) return kRead;
  std::uint8_t encoders = 0, velocities = 0;
  if ((p = checkFlag(c, "encoders", encoders, why)) != kRead) return p;
  if (encoders || version < 2) c.skip(2 * sizeof(std::int32_t));
  if ((p = checkFlag(c, "velocities", velocities, why)) != kRead) return p;
  if (version < 2) c.skip(2 * sizeof(float));
  if (version == 2 && velocities) c.skip(3 * sizeof(double));
  return kRead;
}

}  // namespace

Parse checkPose(Cursor& c, std::string& why) { return pose(c, why); }

Parse checkPart(Cursor& c, const std::string& name, std::string& why) {
  // (Each walk reads the header again and takes only the classes it knows.)
  if (name == "CImage") return image(c, why);
  if (name == "TCamera") return camera(c, why);
  if (name.rfind("CMatrix", 0) == 0) return matrix(c, "matrix", why);
  if (name.rfind("CPose", 0) == 0) return pose(c, why);
  return name.find("PointsMap") != std::string::npos ? pointsMap(c, why) : kOther;
}

Parse checkString(Cursor& c, const char* field, std::string& why, std::uint32_t max_bytes) {
  return string(c, field, why, max_bytes);
}

Parse checkSides(Cursor& c, const char* field, std::uint64_t& rows, std::uint64_t& cols,
                 std::string& why) {
  return sides(c, field, rows, cols, why);
}

Parse checkObservation(Cursor& c, const ObjectHeader& h, std::string& why) {
  // The walk of each observation class, by its name without the namespace.
  static const struct {
    const char* name;
    Parse (*walk)(Cursor&, int, std::string&);
  } kWalks[] = {{"CObservation2DRangeScan", scan2D}, {"CObservation3DRangeScan", scan3D},
                {"CObservationImage", monoImage},     {"CObservationStereoImages", stereoImages},
                {"CObservationPointCloud", pointCloud}, {"CObservationComment", comment},
                {"CObservationRange", ranges},        {"CObservationGPS", gnss},
                {"CObservationIMU", imu},             {"CObservationOdometry", odometry},
                {"CObservationVelodyneScan", checkVelodyneScan},
                {"CObservationRotatingScan", checkRotatingScan},
                {"CObservationBatteryState", checkBatteryState},
                {"CObservationRGBD360", checkRgbd360}};
  for (const auto& w : kWalks) {
    if (h.class_name != w.name) continue;
    const Parse p = w.walk(c, h.version, why);
    if (p != kRead) return p;
    return endOf(c, h) ? kRead : kOther;
  }
  return kOther;
}

}  // namespace upd::mrpt_bridge::detail
