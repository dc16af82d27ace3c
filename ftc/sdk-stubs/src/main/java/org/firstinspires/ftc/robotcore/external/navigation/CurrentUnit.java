// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package org.firstinspires.ftc.robotcore.external.navigation;

public enum CurrentUnit {
    AMPS(1.0), MILLIAMPS(0.001);

    private final double ampsPerUnit;

    CurrentUnit(double ampsPerUnit) {
        this.ampsPerUnit = ampsPerUnit;
    }

    public double toAmps(double value) {
        return value * ampsPerUnit;
    }

    public double toMilliAmps(double value) {
        return value * ampsPerUnit * 1000.0;
    }

    /** value, given in unit, expressed in this unit. */
    public double convert(double value, CurrentUnit unit) {
        return value * unit.ampsPerUnit / ampsPerUnit;
    }
}
