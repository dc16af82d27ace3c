/* motorlab: seed 1's spin-up from rest. See docs/ftc-robot.md. */
package org.firstinspires.ftc.teamcode.motorlab;

import com.qualcomm.robotcore.eventloop.opmode.TeleOp;
import java.util.Map;

/**
 * Spin-up from rest: {@link #restSeconds} at rest, then constant drive for {@link #runSeconds}, then
 * the power is cut and {@link #afterSeconds} more are logged.
 *
 * <p>Relay drive: the bench supply in constant current (seed 1, "First Experiment"), analysed with
 * {@code motorlab analyze spinup}. Hub drive: constant power; the log holds the commanded voltage
 * (power × hub input voltage) and the motor current, for {@code motorlab analyze identify}; it ends at
 * the cut, because a coasting motor (FLOAT) is open-circuit, not driven at the logged 0 V.
 */
@TeleOp(name = "motorlab: spin-up", group = "motorlab")
public class SpinUpOpMode extends DynoOpMode {
    public double restSeconds = 0.5;
    public double runSeconds = 30.0;
    /** Relay drive only: logged after the cut [s]. */
    public double afterSeconds = 2.0;
    /** Hub drive only: the power [-1, 1]. */
    public double hubPower = 1.0;

    @Override
    protected String experiment() {
        return "spinup";
    }

    @Override
    protected String checkRig() {
        if (rig.drive == DynoRig.Drive.RELAY && rig.ina219 == null) {
            return "the relay rig needs the INA219 '" + config.ina219Name + "' (voltage and current)";
        }
        return null;
    }

    @Override
    protected void describe(Map<String, String> fields) {
        fields.put("rest_s", fmt(restSeconds));
        fields.put("run_s", fmt(runSeconds));
        if (rig.drive == DynoRig.Drive.HUB) {
            fields.put("hub_power", fmt(hubPower));
        }
    }

    @Override
    protected boolean step(Sample s) {
        boolean on = s.time >= restSeconds && s.time < restSeconds + runSeconds;
        rig.drive(on, hubPower);
        double after = rig.drive == DynoRig.Drive.HUB ? 0.0 : afterSeconds;
        return s.time < restSeconds + runSeconds + after;
    }
}
