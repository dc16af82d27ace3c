/* motorlab: SysId-style tests of a mechanism driven by the hub. See docs/ftc-robot.md. */
package org.firstinspires.ftc.teamcode.motorlab;

import com.qualcomm.robotcore.hardware.DcMotor;
import java.util.Map;

/**
 * Common part of the quasistatic and dynamic tests of a mechanism (WPILib SysId's four tests): the
 * hub drives the motor with a commanded voltage V, sent as power = V / V_battery; the log holds that
 * voltage and the current; {@code motorlab analyze feedforward} fits kS, kV, kA (and kG). The run
 * stops at the limits: set {@link DynoConfig#maxTravel} for anything with end stops.
 */
public abstract class MechanismOpMode extends DynoOpMode {
    /** Direction of the test: forward (positive voltage) or backward. */
    public boolean forward = true;

    /** The voltage [V] (positive magnitude) to command at time t [s]; NaN when the test is over. */
    protected abstract double volts(double t);

    @Override
    protected String checkRig() {
        if (rig.drive == DynoRig.Drive.RELAY) {
            return "a relay '" + config.relayName + "' is configured: the mechanism tests drive the motor from the hub";
        }
        return null;
    }

    @Override
    protected DcMotor.ZeroPowerBehavior endBehaviour() {
        return DcMotor.ZeroPowerBehavior.BRAKE;
    }

    @Override
    protected void describe(Map<String, String> fields) {
        fields.put("direction", forward ? "forward" : "backward");
    }

    @Override
    protected boolean step(Sample s) {
        double v = volts(s.time);
        if (Double.isNaN(v)) {
            return false;
        }
        rig.setVoltage(forward ? v : -v);
        return true;
    }

    @Override
    public void runOpMode() {
        // Before START, dpad right/left chooses the direction (the stub SDK starts at once).
        if (gamepad1 != null && gamepad1.dpad_left) {
            forward = false;
        } else if (gamepad1 != null && gamepad1.dpad_right) {
            forward = true;
        }
        super.runOpMode();
    }
}
