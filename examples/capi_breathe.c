/* capi_breathe.c: drive the breathing torso from C: a 45-year-old woman breathing deeper than
 * the quiet drive (ribs 0.2, diaphragm 0.25 at 0.25 Hz) for 8 s, lung volume and markers at
 * each frame and the tidal volume, then a snapshot replay that must reproduce the run bit for
 * bit.
 *
 *   cargo build --release
 *   gcc -std=c11 -Iinclude examples/capi_breathe.c -Ltarget/release -lbreathing_torso -lm \
 *       -Wl,-rpath,"$PWD/target/release"
 *   ./a.out
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "breathing_torso.h"

#define FRAME 0.02 /* s between frames (50 Hz) */
#define FRAMES 400

static int check(BtTorso *torso, int rc, const char *what) {
    if (rc != BT_OK) {
        fprintf(stderr, "%s failed (%d): %s\n", what, rc, bt_last_error(torso));
        return 0;
    }
    return 1;
}

int main(void) {
    BtConfig config;
    bt_config_default(&config);
    config.subject.sex = 1; /* female */
    config.subject.age = 45;
    config.drive.frequency = 0.25;
    config.drive.ribs.amplitude = 0.2;
    config.drive.diaphragm.amplitude = 0.25;
    config.drive.diaphragm.phase = 0.1;

    BtTorso *torso = bt_create(&config);
    if (!torso) {
        fprintf(stderr, "bt_create: %s\n", bt_creation_error());
        return 1;
    }
    size_t markers = 0;
    bt_marker_count(torso, &markers);
    double *xyz = malloc(3 * markers * sizeof(double));
    double lung[FRAMES + 1];
    unsigned char *snapshot = NULL;
    size_t snapshot_size = 0;
    int marker_note = 0;

    bt_read(torso, BT_VR_VOLUME_LUNG, &lung[0]);
    for (int k = 1; k <= FRAMES; k++) {
        BtAdvanceStats stats;
        if (!check(torso, bt_advance_to(torso, k * FRAME, &stats), "bt_advance_to")) return 1;
        if (!check(torso, bt_read(torso, BT_VR_VOLUME_LUNG, &lung[k]), "bt_read volume.lung")) return 1;
        int rc = bt_read_markers(torso, xyz, 3 * markers, &markers);
        if (rc != BT_OK && !marker_note) {
            printf("markers unavailable: %s\n", bt_last_error(torso));
            marker_note = 1;
        }
        if (k % 50 == 0) printf("t = %5.2f s  lung volume %.4f L\n", k * FRAME, lung[k]);
        if (k == FRAMES / 2) {
            bt_snapshot(torso, NULL, 0, &snapshot_size);
            snapshot = malloc(snapshot_size);
            if (!check(torso, bt_snapshot(torso, snapshot, snapshot_size, &snapshot_size), "bt_snapshot")) return 1;
        }
    }
    double min = lung[0], max = lung[0];
    for (int k = 0; k <= FRAMES; k++) {
        if (lung[k] < min) min = lung[k];
        if (lung[k] > max) max = lung[k];
    }
    printf("lung volume range %.4f .. %.4f L (tidal %.4f L)\n", min, max, max - min);

    /* Replay the second half from the snapshot: identical to the bit. */
    if (!check(torso, bt_restore(torso, snapshot, snapshot_size), "bt_restore")) return 1;
    for (int k = FRAMES / 2 + 1; k <= FRAMES; k++) {
        double v;
        if (!check(torso, bt_advance_to(torso, k * FRAME, NULL), "bt_advance_to (replay)")) return 1;
        bt_read(torso, BT_VR_VOLUME_LUNG, &v);
        if (memcmp(&v, &lung[k], sizeof v) != 0) {
            fprintf(stderr, "replay differs at frame %d: %.17g vs %.17g\n", k, v, lung[k]);
            return 1;
        }
    }
    printf("replay identical\n");

    /* The right-hand side for external integrators agrees with the model's own integrator:
     * (y(t + dt) - y(t)) / dt approaches f(t, y(t)) for a small dt. Setting the state first
     * makes the integrator start its step at (t, y) rather than continue the step it took
     * past t (it steps past the communication points and reads them off that step). */
    size_t n = 0;
    if (!check(torso, bt_state_dim(torso, &n), "bt_state_dim")) return 1;
    double *y0 = malloc(n * sizeof(double)), *y1 = malloc(n * sizeof(double)), *f = malloc(n * sizeof(double));
    double t0 = 0;
    bt_time(torso, &t0);
    const double dt = 1e-6;
    if (!check(torso, bt_get_state(torso, y0, n), "bt_get_state")) return 1;
    if (!check(torso, bt_rhs(torso, t0, y0, f, n), "bt_rhs")) return 1;
    if (!check(torso, bt_set_state(torso, t0, y0, n), "bt_set_state")) return 1;
    if (!check(torso, bt_advance_to(torso, t0 + dt, NULL), "bt_advance_to (dt)")) return 1;
    bt_get_state(torso, y1, n);
    double err = 0, scale = 0;
    for (size_t i = 0; i < n; i++) {
        double d = (y1[i] - y0[i]) / dt - f[i];
        err += d * d;
        scale += f[i] * f[i];
    }
    printf("state dimension %zu, |(y1 - y0)/dt - f| / |f| = %.2e\n", n, sqrt(err / (scale > 0 ? scale : 1)));
    if (!(sqrt(err) <= 1e-3 * sqrt(scale) + 1e-9)) {
        fprintf(stderr, "bt_rhs disagrees with the integrator\n");
        return 1;
    }
    printf("rhs consistent\n");
    free(y0);
    free(y1);
    free(f);
    free(snapshot);
    free(xyz);
    bt_destroy(torso);
    return 0;
}
