/* flip.h - LDR-FLIP, the perceptual difference of two displayed images
 * (Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström, Fairchild, "FLIP: A
 * Difference Evaluator for Alternating Images", HPG 2020), written from the
 * paper; the details it leaves open (filter radii and normalisation, edge
 * handling, the feature detectors' separable form) follow NVIDIA's reference
 * implementation (BSD-3), read, not copied.
 *
 * Per pixel, in [0, 1]: a colour difference (both images to YCxCz, filtered
 * by the contrast sensitivity of the eye at the viewing condition's pixels per
 * degree, back to linear RGB clamped to [0, 1], to CIELab with the Hunt
 * adjustment, the HyAB distance raised to 0.7 and mapped so that the distance
 * of green to blue is 1) raised to the power 1 - the feature difference (edges
 * and points of the achromatic channel, found by the first and second
 * derivatives of a Gaussian of 0.082 degrees, their largest difference over
 * sqrt 2, to the power 0.5). Identical images give 0 everywhere. */
#pragma once
#include <stdbool.h>

/* The viewing condition: a 0.7 m wide 3840-pixel display seen from 0.7 m (the paper's), 67.02 pixels per degree. */
#define SB_FLIP_PPD_DEFAULT 67.0206
/* Pixels per degree of a display `width_m` wide with `pixels` across, seen from `distance_m`. */
double sb_flip_ppd(double distance_m, double pixels, double width_m);

typedef struct sb_flip_stats {
    double mean, p95, max;   /* over every pixel of the map */
} sb_flip_stats;

/* FLIP of test against ref: w x h pixels of sRGB-encoded RGB in [0, 1] (3 floats a pixel, rows in either order,
 * the same for both). map (w*h floats, or NULL) gets the per-pixel error; ppd <= 0: SB_FLIP_PPD_DEFAULT.
 * Returns the statistics of the map. */
sb_flip_stats sb_flip(const float *ref, const float *test, int w, int h, double ppd, float *map);

/* The two pipelines apart, for tests: the colour difference (before the feature exponent) and the feature
 * difference, each w*h floats. */
void sb_flip_color(const float *ref, const float *test, int w, int h, double ppd, float *out);
void sb_flip_features(const float *ref, const float *test, int w, int h, double ppd, float *out);

/* sRGB-encoded [0, 1] value of a linear one (and back), as images are stored. */
float sb_srgb_encode(float linear);
float sb_srgb_decode(float encoded);
