/* capi_errors.c: how the breathing-torso C ABI reports bad input. Every failure returns a
 * negative BT_ERR_* code and a message naming the culprit; nothing changes on failure.
 *
 *   cargo build --release
 *   gcc -std=c11 -Iinclude examples/capi_errors.c -Ltarget/release -lbreathing_torso -lm \
 *       -Wl,-rpath,"$PWD/target/release"
 *   ./a.out
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "breathing_torso.h"

static int failures = 0;

static void expect(int ok, const char *what, const char *message) {
    if (!ok) {
        printf("FAILED: %s (%s)\n", what, message ? message : "");
        failures++;
    } else {
        printf("ok: %s%s%s\n", what, message && *message ? " -> " : "", message ? message : "");
    }
}

int main(void) {
    BtConfig config;
    expect(bt_config_default(&config) == BT_OK, "default configuration", "");
    expect(config.grid_rows == 10 && config.grid_cols == 6, "default grid is 10 x 6", "");

    /* Key/value configuration is range-checked. */
    int rc = bt_config_set(&config, "subject.age", 200.0);
    expect(rc == BT_ERR_INVALID && strstr(bt_creation_error(), "subject.age"), "age 200 rejected", bt_creation_error());
    rc = bt_config_set(&config, "subject.height", 1.8);
    expect(rc == BT_ERR_INVALID && strstr(bt_creation_error(), "subject.height"), "unknown name rejected", bt_creation_error());
    rc = bt_config_set(&config, "grid.rows", 8.5);
    expect(rc == BT_ERR_INVALID, "non-integral grid.rows rejected", bt_creation_error());
    expect(bt_config_set(&config, "grid.rows", 8) == BT_OK && config.grid_rows == 8, "grid.rows = 8", "");
    expect(config.subject.age == 30.0, "rejected values changed nothing", "");

    /* A bad configuration: bt_create returns NULL and says why. */
    BtConfig bad = config;
    bad.subject.stature = 5.0;
    BtTorso *none = bt_create(&bad);
    expect(none == NULL && strstr(bt_creation_error(), "subject.stature"), "stature 5 m rejected", bt_creation_error());

    BtTorso *torso = bt_create(&config);
    expect(torso != NULL, "model built", bt_creation_error());
    if (!torso) return 1;

    /* Inputs: not finite, out of range, unknown group. */
    rc = bt_set_activation(torso, 0, NAN);
    expect(rc == BT_ERR_INVALID && strstr(bt_last_error(torso), "activation.diaphragm"), "NaN activation rejected", bt_last_error(torso));
    rc = bt_set_activation_by_name(torso, "scalenes", 1.5);
    expect(rc == BT_ERR_INVALID && strstr(bt_last_error(torso), "activation.scalenes"), "activation 1.5 rejected", bt_last_error(torso));
    rc = bt_set_activation(torso, 42, 0.5);
    expect(rc == BT_ERR_INVALID, "group 42 rejected", bt_last_error(torso));
    expect(bt_set_activation(torso, 0, 0.3) == BT_OK, "activation 0.3 accepted", "");
    double a = -1;
    expect(bt_read(torso, BT_VR_ACTIVATION_DIAPHRAGM, &a) == BT_OK && a == 0.3, "input reads back", "");

    /* The airway-opening pressure: out of range is refused and changes nothing; a
       ventilator's 5 cmH2O reaches the alveolar and pleural pressures at once. */
    double alveolar = 1, pleural = 0, pleural_after = 0;
    bt_read(torso, BT_VR_PRESSURE_PLEURAL, &pleural);
    rc = bt_set_airway_opening(torso, 1e6);
    expect(rc == BT_ERR_INVALID && strstr(bt_last_error(torso), "pressure.airway_opening"), "airway pressure 1e6 Pa rejected", bt_last_error(torso));
    expect(bt_read(torso, BT_VR_PRESSURE_ALVEOLAR, &alveolar) == BT_OK && alveolar == 0.0, "rejected pressure kept the state", "");
    expect(bt_set_airway_opening(torso, 5 * 98.0665) == BT_OK, "airway pressure 5 cmH2O accepted", bt_last_error(torso));
    bt_read(torso, BT_VR_PRESSURE_ALVEOLAR, &alveolar);
    bt_read(torso, BT_VR_PRESSURE_PLEURAL, &pleural_after);
    expect(fabs(alveolar - 5 * 98.0665) < 1e-9 && fabs(pleural_after - pleural - 5 * 98.0665) < 1e-9,
           "airway pressure reaches the alveoli and the pleura without a step", "");
    expect(bt_set_airway_opening(torso, 0.0) == BT_OK, "airway pressure back to 0", "");

    BtDrive drive;
    expect(bt_get_drive(torso, &drive) == BT_OK, "drive read", "");
    drive.frequency = 10.0;
    rc = bt_set_drive(torso, &drive);
    expect(rc == BT_ERR_INVALID && strstr(bt_last_error(torso), "drive.frequency"), "drive at 10 Hz rejected", bt_last_error(torso));
    expect(bt_get_drive(torso, &drive) == BT_OK && drive.frequency == 0.25 && drive.inspiratory_fraction == 0.5,
           "drive unchanged by the refused set, inspiratory fraction 0.5 (the sine)", "");
    drive.inspiratory_fraction = 0.9;
    rc = bt_set_drive(torso, &drive);
    expect(rc == BT_ERR_INVALID && strstr(bt_last_error(torso), "drive.inspiratory_fraction"), "Ti/Ttot 0.9 rejected", bt_last_error(torso));
    drive.inspiratory_fraction = 0.4;
    expect(bt_set_drive(torso, &drive) == BT_OK, "Ti/Ttot 0.4 accepted", bt_last_error(torso));
    double fraction = 0;
    expect(bt_read(torso, BT_VR_DRIVE_INSPIRATORY_FRACTION, &fraction) == BT_OK && fraction == 0.4,
           "drive.inspiratory_fraction reads back 0.4", "");

    /* Reading by value reference and by name. */
    double v = 0;
    expect(bt_read(torso, BT_VR_SUBJECT_AGE, &v) == BT_OK && v == 30.0, "subject.age reads 30", "");
    expect(bt_read(torso, BT_VR_GRID_ROWS, &v) == BT_OK && v == 8.0, "grid.rows reads 8", "");
    expect(bt_read(torso, BT_VR_TIME, &v) == BT_OK && v == 0.0, "time reads 0", "");
    expect(bt_read(torso, 99999u, &v) == BT_ERR_INVALID, "unknown value reference rejected", bt_last_error(torso));
    expect(bt_read_by_name(torso, "marker[200].x", &v) == BT_OK && v == 0.0, "marker beyond the grid reads 0", "");
    expect(bt_read(torso, BT_VR_MARKER(200, 1), &v) == BT_OK && v == 0.0, "same by value reference", "");

    /* Caller buffers are sized explicitly. */
    size_t count = 0;
    double small[3];
    rc = bt_read_markers(torso, small, 3, &count);
    expect(rc == BT_ERR_BUFFER && count == 48, "marker buffer too small, count = 48", bt_last_error(torso));

    size_t vertices = 0, triangles = 0;
    rc = bt_skin_sizes(torso, &vertices, &triangles);
    expect(rc == BT_OK && vertices > 0 && triangles > 0, "skin sizes answered", bt_last_error(torso));
    rc = bt_read_skin(torso, small, 3, NULL, 0);
    expect(rc == BT_ERR_BUFFER && strstr(bt_last_error(torso), "skin vertex buffer holds 3 doubles"),
           "skin vertex buffer too small", bt_last_error(torso));
    rc = bt_read_skin(torso, NULL, 0, NULL, 0);
    expect(rc == BT_ERR_NULL, "skin read with no buffer at all", bt_last_error(torso));

    /* Snapshots: size query, round trip, garbage rejected. */
    size_t size = 0;
    rc = bt_snapshot(torso, NULL, 0, &size);
    expect(rc == BT_ERR_BUFFER && size > 0, "snapshot size query", "");
    unsigned char *buffer = malloc(size);
    expect(bt_snapshot(torso, buffer, size, &size) == BT_OK, "snapshot written", bt_last_error(torso));
    expect(bt_set_activation(torso, 0, 0.9) == BT_OK, "activation changed", "");
    expect(bt_restore(torso, buffer, size) == BT_OK, "snapshot restored", bt_last_error(torso));
    expect(bt_read(torso, BT_VR_ACTIVATION_DIAPHRAGM, &a) == BT_OK && a == 0.3, "restored input is 0.3", "");
    unsigned char garbage[64];
    memset(garbage, 0x5a, sizeof garbage);
    rc = bt_restore(torso, garbage, sizeof garbage);
    expect(rc != BT_OK && strlen(bt_last_error(torso)) > 0, "garbage snapshot rejected", bt_last_error(torso));
    free(buffer);

    /* The right-hand side checks the state length. */
    size_t dim = 0;
    expect(bt_state_dim(torso, &dim) == BT_OK && dim > 0, "state dimension", "");
    double y[4], dydt[4];
    rc = bt_rhs(torso, 0.0, y, dydt, 4);
    expect(dim == 4 || rc == BT_ERR_INVALID, "wrong state length rejected", bt_last_error(torso));

    /* NULL handles and arguments. */
    expect(bt_time(NULL, &v) == BT_ERR_NULL, "NULL handle rejected", "");
    expect(bt_time(torso, NULL) == BT_ERR_NULL, "NULL output rejected", bt_last_error(torso));
    expect(bt_read_by_name(torso, NULL, &v) == BT_ERR_NULL, "NULL name rejected", bt_last_error(torso));

    bt_destroy(torso);
    bt_destroy(NULL);
    if (failures) {
        printf("%d checks failed\n", failures);
        return 1;
    }
    printf("all checks passed\n");
    return 0;
}
