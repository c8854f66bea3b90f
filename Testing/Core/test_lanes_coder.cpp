// SPDX-License-Identifier: BSD-3-Clause
// Lanes frames (entropy/lanes_coder.hpp): any byte stream comes back byte for byte, at close to its
// order-0 entropy; damaged frames are refused with what is wrong, never read out of bounds; coded
// payloads take the lanes frame unless zstd's is more than 2% smaller (or the stage they are
// told), and decode the same values either way.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "afam/base/errors.hpp"
#include "afam/entropy/lanes_coder.hpp"
#include "afam/format/block_codec.hpp"

using namespace afam;

namespace {

/// Bytes drawn from a two-sided geometric law of scale `s` around 0 (zigzag, as codes are).
std::vector<uint8_t> skewedBytes(size_t n, double s, unsigned seed) {
  std::mt19937 rng(seed);
  std::geometric_distribution<int> g(1.0 / (1.0 + s));
  std::vector<uint8_t> v(n);
  for (auto& b : v) b = uint8_t(std::min(255, g(rng)));
  return v;
}

double entropyBytes(const std::vector<uint8_t>& v) {
  double count[256] = {};
  for (const uint8_t b : v) ++count[b];
  double bits = 0;
  for (const double c : count)
    if (c > 0) bits -= c * std::log2(c / double(v.size()));
  return bits / 8;
}

int64_t decode(const std::vector<uint8_t>& frame, std::vector<uint8_t>& out, std::string& error,
               bool vectorPath = true) {
  out.assign(lanes::frameSymbols(frame.data(), frame.size()) + 1, 0xAB);
  const char* e = nullptr;
  const int64_t n =
      lanes::decodeFrame(frame.data(), frame.size(), out.data(), out.size(), &e, vectorPath);
  error = e ? e : "";
  return n;
}

}  // namespace

TEST(LanesCoder, EveryStreamComesBackByteForByteNearItsEntropy) {
  std::mt19937 rng(3);
  std::vector<std::vector<uint8_t>> streams = {{}, {7}, std::vector<uint8_t>(5000, 42)};
  for (const size_t n : {1, 31, 63, 64, 65, 2047, 2048, 2049, 100000})
    streams.push_back(skewedBytes(n, 3.0, unsigned(n)));
  std::vector<uint8_t> uniform(70000);
  for (auto& b : uniform) b = uint8_t(rng());
  streams.push_back(uniform);
  for (const auto& s : streams) {
    std::vector<uint8_t> frame, out;
    lanes::appendFrame(s, frame);
    std::string error;
    ASSERT_EQ(decode(frame, out, error), int64_t(s.size())) << error;
    EXPECT_TRUE(std::equal(s.begin(), s.end(), out.begin())) << s.size() << " bytes";
    std::vector<uint8_t> scalar;  // the CPU's vector path (where it has one) and the scalar loop
    ASSERT_EQ(decode(frame, scalar, error, false), int64_t(s.size())) << error;
    EXPECT_EQ(scalar, out);
    EXPECT_EQ(frame[8], lanes::lanesFor(s.size()));
    if (s.size() >= 2048) {  // the table and states amortised: within 1% and 160 B of H0
      EXPECT_LE(double(frame.size()), 1.01 * entropyBytes(s) + 160 + 4 * 32) << s.size();
    }
  }
  // One byte value: no words at all, the frame is its header, table and states.
  std::vector<uint8_t> frame;
  lanes::appendFrame(std::vector<uint8_t>(5000, 42), frame);
  EXPECT_LE(frame.size(), lanes::kFixedHeaderBytes + 43 + 2 + 4 * 32);
}

TEST(LanesCoder, DamagedFramesAreRefusedWithTheReason) {
  const std::vector<uint8_t> s = skewedBytes(20000, 5.0, 9);
  std::vector<uint8_t> frame, out;
  lanes::appendFrame(s, frame);
  std::string error;
  auto refused = [&](std::vector<uint8_t> f, const std::string& why) {
    for (const bool vectorPath : {true, false}) {
      EXPECT_EQ(decode(f, out, error, vectorPath), -1) << why;
      EXPECT_EQ(error, why);
    }
  };
  std::vector<uint8_t> f = frame;
  f[0] = 'X';
  refused(f, "is not a lanes frame");
  f = frame;
  f[8] = 0;
  refused(f, "names an invalid lane count");
  f = frame;
  f[8] = 33;
  refused(f, "names an invalid lane count");
  f = frame;
  f[10] = uint8_t(f[10] + 1);  // byte 0's frequency off by one
  EXPECT_EQ(decode(f, out, error), -1);
  f = frame;
  f.resize(f.size() - 2);
  EXPECT_EQ(decode(f, out, error), -1);
  f = frame;
  f.resize(f.size() - 1);
  refused(f, "is truncated");
  f = frame;
  f.resize(12);
  EXPECT_EQ(decode(f, out, error), -1);
  // More bytes than the caller's buffer holds: refused before anything is written.
  std::vector<uint8_t> small(100, 0);
  const char* e = nullptr;
  EXPECT_EQ(lanes::decodeFrame(frame.data(), frame.size(), small.data(), small.size(), &e), -1);
  EXPECT_STREQ(e, "decodes to more bytes than its block holds");
  // Flipped bits in the words: the states do not end where the encoder began.
  std::mt19937 rng(1);
  int caught = 0;
  for (int t = 0; t < 200; ++t) {
    f = frame;
    const size_t at = f.size() - 1 - rng() % 2000;
    f[at] = uint8_t(f[at] ^ (1u << (rng() % 8)));
    caught += decode(f, out, error) == -1;
    std::vector<uint8_t> scalar;  // the same verdict and bytes on both paths
    EXPECT_EQ(decode(f, scalar, error, false), decode(f, out, error));
    EXPECT_EQ(scalar, out);
  }
  EXPECT_GE(caught, 195);
}

TEST(LanesCoder, CodedPayloadsTakeTheLanesFrameUnlessZstdIsClearlySmaller) {
  const Int3 n{24, 20, 16};
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, 1);
  const size_t count = size_t(n[0]) * size_t(n[1]) * size_t(n[2]);
  std::vector<float> noisy(count), smooth(count);
  for (size_t i = 0; i < noisy.size(); ++i) {
    noisy[i] = float(100 + noise(rng));  // a scan's noise: Lorenzo codes of 1 byte
    smooth[i] = float(std::sin(0.01 * double(i)));
  }
  for (const auto* v : {&noisy, &smooth}) {
    std::vector<uint8_t> z, l, chosen;
    std::vector<float> rz, rl, rs, dz(v->size()), dl(v->size());
    const Predictor p = Predictor::IntegerLorenzo;
    ASSERT_TRUE(encodeValues(v->data(), n, 0.5, p, {15, EntropyStage::Zstd}, z, rz));
    ASSERT_TRUE(encodeValues(v->data(), n, 0.5, p, {15, EntropyStage::Lanes}, l, rl));
    ASSERT_TRUE(encodeValues(v->data(), n, 0.5, p, {15, EntropyStage::Auto}, chosen, rs));
    EXPECT_FALSE(payloadIsLanesCoded(z.data(), z.size()));
    EXPECT_TRUE(payloadIsLanesCoded(l.data(), l.size()));
    const bool lanesKept = double(l.size() - 17) <= 1.02 * double(z.size() - 17);
    EXPECT_EQ(chosen, lanesKept ? l : z);
    decodeValues(z.data(), z.size(), n, dz.data(), "zstd");
    decodeValues(l.data(), l.size(), n, dl.data(), "lanes");
    EXPECT_EQ(0, std::memcmp(dz.data(), dl.data(), dz.size() * 4));
    EXPECT_EQ(0, std::memcmp(dl.data(), rl.data(), dl.size() * 4));
  }
  // A scan's noise, in a block of a scan's size, codes smaller in lanes frames (zstd's Huffman
  // rounds code lengths to whole bits, rANS does not; below some 10^4 values the lanes frame's
  // table and states cost more than that gains).
  const Int3 big{40, 40, 40};
  std::vector<float> scan(size_t(64000));
  for (auto& x : scan) x = float(100 + noise(rng));
  std::vector<uint8_t> z, l;
  std::vector<float> r;
  ASSERT_TRUE(encodeValues(scan.data(), big, 0.5, Predictor::IntegerLorenzo,
                           {15, EntropyStage::Zstd}, z, r));
  ASSERT_TRUE(encodeValues(scan.data(), big, 0.5, Predictor::IntegerLorenzo,
                           {15, EntropyStage::Lanes}, l, r));
  EXPECT_LT(l.size(), z.size());
  // A damaged lanes payload is a FormatError naming the frame.
  l[l.size() / 2] ^= 0x10;
  std::vector<float> out(scan.size());
  try {
    decodeValues(l.data(), l.size(), big, out.data(), "block (1, 2, 3)");
    ADD_FAILURE() << "a damaged lanes payload decoded";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("block (1, 2, 3): coded payload"), std::string::npos)
        << e.what();
  }
}
