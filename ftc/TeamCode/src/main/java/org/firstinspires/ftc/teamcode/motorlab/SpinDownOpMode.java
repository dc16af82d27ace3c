/* motorlab: seed 1's flywheel spin-down. See docs/ftc-robot.md. */
package org.firstinspires.ftc.teamcode.motorlab;

import com.qualcomm.robotcore.eventloop.opmode.TeleOp;
import java.util.Map;

/**
 * Spin-down (seed 1, "Flywheel and INA219 Experiment"): drive for {@link #runSeconds}, cut the power,
 * log the coast until the shaft has stood still for {@link #stillSeconds} (or {@link #coastSeconds}).
 *
 * <p>Relay drive (the seed's rig): the bench supply drives the motor through the relay, the INA219
 * reads the bus voltage, which is the back-EMF K·ω once the relay opens: {@code motorlab analyze
 * spindown FILE --inertia J} gives K, b and Tf. Hub drive: the hub powers the motor and the cut is power
 * 0 with FLOAT; the motor terminals then float, so no back-EMF is measured and the log has only
 * {@code time_ms encoder_counts}; the header's {@code cutoff_s} is the instant to pass as
 * {@code --cutoff} (γ = b/J and Tf/J only).
 */
@TeleOp(name = "motorlab: spin-down", group = "motorlab")
public class SpinDownOpMode extends DynoOpMode {
    /** Powered phase [s] (long enough to reach a steady speed). */
    public double runSeconds = 20.0;
    /** Longest coast logged [s]. */
    public double coastSeconds = 90.0;
    /** The coast ends once the encoder has not moved for this long [s]. */
    public double stillSeconds = 1.0;
    /** Hub drive only: the power [-1, 1]. */
    public double hubPower = 1.0;
    private double stillSince = Double.NaN;
    private int lastCounts;

    @Override
    protected String experiment() {
        return "spindown";
    }

    @Override
    protected String checkRig() {
        if (rig.drive == DynoRig.Drive.RELAY && rig.ina219 == null) {
            return "the relay rig needs the INA219 '" + config.ina219Name + "' (its bus voltage is the back-EMF)";
        }
        return null;
    }

    @Override
    protected boolean powerColumns() {
        return rig.drive == DynoRig.Drive.RELAY;
    }

    @Override
    protected void describe(Map<String, String> fields) {
        fields.put("run_s", fmt(runSeconds));
        fields.put("coast_s", fmt(coastSeconds));
        if (rig.drive == DynoRig.Drive.HUB) {
            fields.put("hub_power", fmt(hubPower));
            fields.put("cutoff_s", fmt(runSeconds));
        }
    }

    @Override
    protected boolean step(Sample s) {
        if (s.time < runSeconds) {
            rig.drive(true, hubPower);
            lastCounts = s.counts;
            return true;
        }
        rig.drive(false, 0.0);
        if (s.counts != lastCounts) {
            stillSince = Double.NaN;
        } else if (Double.isNaN(stillSince)) {
            stillSince = s.time;
        } else if (s.time - stillSince >= stillSeconds) {
            return false;
        }
        lastCounts = s.counts;
        return s.time < runSeconds + coastSeconds;
    }
}
