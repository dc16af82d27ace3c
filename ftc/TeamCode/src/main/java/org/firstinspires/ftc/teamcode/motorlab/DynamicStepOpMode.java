/* motorlab: dynamic voltage step of a mechanism. */
package org.firstinspires.ftc.teamcode.motorlab;

import com.qualcomm.robotcore.eventloop.opmode.TeleOp;
import java.util.Map;

/** Dynamic test: {@link #restSeconds} at 0 V, then a step to {@link #stepVolts} for {@link #stepSeconds}. */
@TeleOp(name = "motorlab: dynamic step", group = "motorlab")
public class DynamicStepOpMode extends MechanismOpMode {
    public double restSeconds = 0.25;
    public double stepVolts = 6.0;
    public double stepSeconds = 2.0;

    @Override
    protected String experiment() {
        return "dynamic";
    }

    @Override
    protected void describe(Map<String, String> fields) {
        super.describe(fields);
        fields.put("rest_s", fmt(restSeconds));
        fields.put("step_V", fmt(stepVolts));
    }

    @Override
    protected double volts(double t) {
        if (t > restSeconds + stepSeconds) {
            return Double.NaN;
        }
        return t < restSeconds ? 0.0 : stepVolts;
    }
}
