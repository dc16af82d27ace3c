/* motorlab: quasistatic voltage ramp of a mechanism. */
package org.firstinspires.ftc.teamcode.motorlab;

import com.qualcomm.robotcore.eventloop.opmode.TeleOp;
import java.util.Map;

/** Quasistatic test: V = rate·t until {@link #maxVolts} or a limit (SysId's slow ramp). */
@TeleOp(name = "motorlab: quasistatic ramp", group = "motorlab")
public class QuasistaticOpMode extends MechanismOpMode {
    /** Ramp rate [V/s]: slow enough that acceleration is negligible. */
    public double rampVoltsPerSecond = 0.5;
    /** The ramp ends here [V]. */
    public double maxVolts = 10.0;

    @Override
    protected String experiment() {
        return "quasistatic";
    }

    @Override
    protected void describe(Map<String, String> fields) {
        super.describe(fields);
        fields.put("ramp_V_per_s", fmt(rampVoltsPerSecond));
        fields.put("max_V", fmt(maxVolts));
    }

    @Override
    protected double volts(double t) {
        double v = rampVoltsPerSecond * t;
        return v > maxVolts ? Double.NaN : v;
    }
}
