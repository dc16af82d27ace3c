/* motorlab: limits that stop the motor. */
package org.firstinspires.ftc.teamcode.motorlab;

import java.util.Locale;

/** Time, current, speed and travel limits; check() names the first one exceeded. */
public final class Limits {
    private final DynoConfig config;
    private final int startCounts;

    public Limits(DynoConfig config, int startCounts) {
        this.config = config;
        this.startCounts = startCounts;
    }

    /** Why the motor must stop now, or null. */
    public String check(Sample s) {
        if (config.maxSeconds > 0 && s.time > config.maxSeconds) {
            return String.format(Locale.US, "time limit %.1f s", config.maxSeconds);
        }
        if (config.maxCurrent > 0 && Math.abs(s.current) > config.maxCurrent) {
            return String.format(Locale.US, "current %.2f A above the limit %.2f A", s.current, config.maxCurrent);
        }
        if (config.maxSpeed > 0 && Math.abs(s.velocity) > config.maxSpeed) {
            return String.format(Locale.US, "speed %.0f counts/s above the limit %.0f", s.velocity, config.maxSpeed);
        }
        if (config.maxTravel > 0 && Math.abs(s.counts - startCounts) > config.maxTravel) {
            return String.format(Locale.US, "travel %d counts above the limit %.0f", s.counts - startCounts,
                    config.maxTravel);
        }
        return null;
    }
}
