/* motorlab: the settings of the dynamometer OpModes (edit the defaults here). See docs/ftc-robot.md. */
package org.firstinspires.ftc.teamcode.motorlab;

/** Device names, the motor under test and the safety limits. Public fields: edit them in one place. */
public class DynoConfig {
    // ---- names in the robot configuration -----------------------------------------------------------
    /** The motor port whose encoder (and, for hub drive, power) is used. */
    public String motorName = "dyno_motor";
    /** INA219 configured as "INA219 current/voltage sensor (motorlab)"; optional for hub drive. */
    public String ina219Name = "ina219";
    /** Digital channel driving the relay between bench supply and motor; absent = the hub drives. */
    public String relayName = "relay";
    /** Relay closed (supply connected) when the channel is high; false for active-low modules. */
    public boolean relayActiveHigh = true;

    // ---- the motor, written in the log header -----------------------------------------------------------
    /** motorlab catalogue key or any name (`motorlab motors` lists the keys). */
    public String motor = "neverest40";
    /** Encoder counts per revolution of the counted shaft [count/rev] (NeveRest 40: 1120 at the output). */
    public double countsPerRevolution = 1120;
    /** Gearbox ratio of the gearmotor (motor turns per output turn). */
    public double gearRatio = 40;
    /** Reverse the motor direction (and so the sign of counts). */
    public boolean reverse = false;

    // ---- INA219 ------------------------------------------------------------------------------------------
    public Ina219.Parameters ina219 = new Ina219.Parameters();

    // ---- limits that stop the motor (0 disables one) ----------------------------------------------------------
    /** Longest run [s]. */
    public double maxSeconds = 180;
    /** Largest |current| [A] (INA219, or the hub's motor current). */
    public double maxCurrent = 6.0;
    /** Largest |encoder velocity| [counts/s], as the hub reports it. */
    public double maxSpeed = 6000;
    /** Largest travel from the start [counts]: set it for arms and elevators. */
    public double maxTravel = 0;
    /** Stop when gamepad 1's B is pressed. */
    public boolean stopOnB = true;

    /** Folder under the controller's FIRST folder where logs go (/sdcard/FIRST/motorlab). */
    public String folder = "motorlab";
}
