/* Colour maps of the quantity modes, in linear RGB, and the conversion to 8-bit sRGB.
 *
 * Stress ratio goes from blue (0) through yellow to red (1, the modulus of rupture reached), a
 * sequential map built on the perceptual "viridis"-like control points for age, a
 * white-to-reddish-brown ramp for reaction wood, and a qualitative palette (Okabe-Ito, safe for
 * colour-blind readers) for branch orders. Control points are sRGB, converted to linear at use. */
#include "writers.h"

#include <math.h>
#include <string.h>

static void ramp(const float (*pts)[3], int n, double t, float rgb[3])
{
    if (!(t >= 0.0))
        t = 0.0;
    if (t > 1.0)
        t = 1.0;
    double x = t * (n - 1);
    int i = (int)x;
    if (i >= n - 1)
        i = n - 2;
    double f = x - i;
    for (int k = 0; k < 3; k++)
        rgb[k] = (float)((1.0 - f) * pts[i][k] + f * pts[i + 1][k]);
}

/* sRGB control points converted to linear once at use */
static float srgb_to_linear(float c)
{
    return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}

void cbm__colormap(cbm_color_by by, double t, float rgb[3])
{
    static const float stress[5][3] = {{0.19f, 0.33f, 0.72f},
                                       {0.35f, 0.70f, 0.85f},
                                       {0.99f, 0.90f, 0.45f},
                                       {0.96f, 0.43f, 0.20f},
                                       {0.70f, 0.05f, 0.10f}};
    static const float viridis[5][3] = {{0.267f, 0.005f, 0.329f},
                                        {0.229f, 0.322f, 0.546f},
                                        {0.128f, 0.567f, 0.551f},
                                        {0.369f, 0.789f, 0.383f},
                                        {0.993f, 0.906f, 0.144f}};
    static const float react[3][3] = {
        {0.93f, 0.90f, 0.82f}, {0.80f, 0.45f, 0.25f}, {0.45f, 0.12f, 0.08f}};
    static const float okabe[8][3] = {
        {0.35f, 0.25f, 0.15f}, {0.90f, 0.62f, 0.00f}, {0.34f, 0.71f, 0.91f}, {0.00f, 0.62f, 0.45f},
        {0.94f, 0.89f, 0.26f}, {0.00f, 0.45f, 0.70f}, {0.84f, 0.37f, 0.00f}, {0.80f, 0.47f, 0.65f}};
    float c[3];
    switch (by) {
    case CBM_COLOR_STRESS:
    case CBM_COLOR_STRESS_MPA:
        ramp(stress, 5, t, c);
        break;
    case CBM_COLOR_REACTION:
        ramp(react, 3, t, c);
        break;
    case CBM_COLOR_ORDER: {
        int i = (int)lround(t);
        if (i < 0)
            i = 0;
        memcpy(c, okabe[i % 8], sizeof c);
        break;
    }
    case CBM_COLOR_AGE:
    default:
        ramp(viridis, 5, t, c);
        break;
    }
    for (int k = 0; k < 3; k++)
        rgb[k] = srgb_to_linear(c[k]);
}

uint8_t cbm__srgb8(double c)
{
    if (!(c > 0.0))
        return 0;
    if (c >= 1.0)
        return 255;
    double s = c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
    return (uint8_t)lround(s * 255.0);
}
