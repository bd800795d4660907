/* capi_skin.c: the whole deformed skin from C: the triangles once, the vertices every frame,
 * through a quiet breath at level of detail 0; checks that the mesh is a closed surface,
 * that every marker lies on the skin at the start (the equilibrium of the drive's start) and after inspiration (the markers are points of
 * the skin's triangles), and that the skin moves.
 *
 *   cargo build --release
 *   gcc -std=c11 -Iinclude examples/capi_skin.c -Ltarget/release -lbreathing_torso -lm \
 *       -Wl,-rpath,"$PWD/target/release"
 *   ./a.out
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "breathing_torso.h"

#define FRAME (1.0 / 56.0) /* s between frames */
#define FRAMES 112         /* 2 s: the inspiration of a 0.25 Hz breath */

static int failures = 0;

static void expect(int ok, const char *what) {
    printf("%s: %s\n", ok ? "ok" : "FAILED", what);
    if (!ok) failures++;
}

static double dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Distance from point p to triangle (a, b, c): the closest point by the Voronoi regions of
 * the triangle's vertices, edges and face. */
static double point_triangle_distance(const double *p, const double *a, const double *b, const double *c) {
    double ab[3], ac[3], ap[3], q[3];
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ap[k] = p[k] - a[k];
    }
    double d1 = dot(ab, ap), d2 = dot(ac, ap);
    double v, w;
    if (d1 <= 0 && d2 <= 0) {
        v = 0, w = 0;
    } else {
        double bp[3], cp[3];
        for (int k = 0; k < 3; k++) {
            bp[k] = p[k] - b[k];
            cp[k] = p[k] - c[k];
        }
        double d3 = dot(ab, bp), d4 = dot(ac, bp), d5 = dot(ab, cp), d6 = dot(ac, cp);
        double va = d3 * d6 - d5 * d4, vb = d5 * d2 - d1 * d6, vc = d1 * d4 - d3 * d2;
        if (d3 >= 0 && d4 <= d3) {
            v = 1, w = 0;
        } else if (d6 >= 0 && d5 <= d6) {
            v = 0, w = 1;
        } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
            v = d1 / (d1 - d3), w = 0;
        } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
            v = 0, w = d2 / (d2 - d6);
        } else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
            w = (d4 - d3) / ((d4 - d3) + (d5 - d6)), v = 1 - w;
        } else {
            double denom = 1.0 / (va + vb + vc);
            v = vb * denom, w = vc * denom;
        }
    }
    for (int k = 0; k < 3; k++) q[k] = a[k] + v * ab[k] + w * ac[k] - p[k];
    return sqrt(dot(q, q));
}

/* The largest distance from a marker to the nearest skin triangle [m]. */
static double markers_off_skin(const double *markers, size_t nm, const double *xyz, const uint32_t *tri, size_t nt) {
    double worst = 0;
    for (size_t m = 0; m < nm; m++) {
        double best = INFINITY;
        for (size_t t = 0; t < nt; t++) {
            double d = point_triangle_distance(&markers[3 * m], &xyz[3 * tri[3 * t]], &xyz[3 * tri[3 * t + 1]],
                                               &xyz[3 * tri[3 * t + 2]]);
            if (d < best) best = d;
        }
        if (best > worst) worst = best;
    }
    return worst;
}

int main(void) {
    BtConfig config;
    bt_config_default(&config);
    config.level_of_detail = 0;
    config.drive.frequency = 0.25;
    config.drive.ribs.amplitude = 0.12;
    config.drive.diaphragm.amplitude = 0.30;
    BtTorso *torso = bt_create(&config);
    if (!torso) {
        fprintf(stderr, "bt_create: %s\n", bt_creation_error());
        return 1;
    }

    size_t nv = 0, nt = 0, nm = 0;
    if (bt_skin_sizes(torso, &nv, &nt) != BT_OK) {
        fprintf(stderr, "bt_skin_sizes: %s\n", bt_last_error(torso));
        return 1;
    }
    printf("skin: %zu vertices, %zu triangles\n", nv, nt);
    double *rest = malloc(3 * nv * sizeof *rest), *xyz = malloc(3 * nv * sizeof *xyz);
    uint32_t *tri = malloc(3 * nt * sizeof *tri);
    double markers[3 * 256];
    /* Triangles once (with the rest vertices), then vertices only. */
    if (bt_read_skin(torso, rest, 3 * nv, tri, 3 * nt) != BT_OK ||
        bt_read_markers(torso, markers, 3 * 256, &nm) != BT_OK) {
        fprintf(stderr, "reading the rest skin: %s\n", bt_last_error(torso));
        return 1;
    }

    int indices_ok = 1;
    for (size_t i = 0; i < 3 * nt; i++) indices_ok &= tri[i] < nv;
    for (size_t t = 0; t < nt; t++)
        indices_ok &= tri[3 * t] != tri[3 * t + 1] && tri[3 * t + 1] != tri[3 * t + 2] && tri[3 * t] != tri[3 * t + 2];
    expect(nv > 0 && nt > 0 && indices_ok, "triangles index three distinct vertices of the skin");
    /* A closed surface of sphere topology: V - E + F = 2 with E = 3F / 2. */
    expect(2 * nv == nt + 4, "the skin is a closed surface (V - T / 2 = 2)");
    double off = markers_off_skin(markers, nm, rest, tri, nt);
    printf("rest: markers at most %.3g mm off the skin\n", 1e3 * off);
    expect(off < 1e-6, "at rest every marker lies on the skin (within 1 um)");

    /* The run starts at the static equilibrium of the drive's start, which for a sine drive
     * is the activation of the breath's mid-point: the largest displacement from the start
     * over the frames (the breath's peak within the 2 s), not the last frame's. */
    double moved = 0;
    for (int k = 1; k <= FRAMES; k++) {
        if (bt_advance_to(torso, k * FRAME, NULL) != BT_OK || bt_read_skin(torso, xyz, 3 * nv, NULL, 0) != BT_OK) {
            fprintf(stderr, "frame %d: %s\n", k, bt_last_error(torso));
            return 1;
        }
        for (size_t i = 0; i < nv; i++) {
            double d[3] = {xyz[3 * i] - rest[3 * i], xyz[3 * i + 1] - rest[3 * i + 1], xyz[3 * i + 2] - rest[3 * i + 2]};
            double m = sqrt(dot(d, d));
            if (m > moved) moved = m;
        }
    }
    printf("after %.1f s: the skin moved up to %.2f mm\n", FRAMES * FRAME, 1e3 * moved);
    expect(moved > 1e-3 && moved < 3e-2, "inspiration moves the skin by 1-30 mm at most");
    if (bt_read_markers(torso, markers, 3 * 256, &nm) != BT_OK) {
        fprintf(stderr, "bt_read_markers: %s\n", bt_last_error(torso));
        return 1;
    }
    off = markers_off_skin(markers, nm, xyz, tri, nt);
    printf("inspired: markers at most %.3g mm off the skin\n", 1e3 * off);
    expect(off < 1e-6, "after inspiration every marker lies on the moved skin (within 1 um)");

    free(rest);
    free(xyz);
    free(tri);
    bt_destroy(torso);
    if (failures) {
        printf("%d checks failed\n", failures);
        return 1;
    }
    printf("all skin checks passed\n");
    return 0;
}
