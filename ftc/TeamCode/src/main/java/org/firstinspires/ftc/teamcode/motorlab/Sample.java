/* motorlab: one reading of the dynamometer. */
package org.firstinspires.ftc.teamcode.motorlab;

/** One loop's readings: time [s], encoder counts, hub velocity [counts/s], voltage [V], current [A]. */
public final class Sample {
    public double time;
    public int counts;
    public double velocity;
    /** INA219 bus voltage, or for hub drive the commanded voltage (power × hub input voltage). */
    public double voltage;
    /** INA219 shunt current, or for hub drive the hub's motor current signed by the power. */
    public double current;
}
