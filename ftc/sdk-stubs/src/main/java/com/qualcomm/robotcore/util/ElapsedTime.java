// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.util;

import java.util.Locale;
import java.util.concurrent.TimeUnit;

/**
 * A stopwatch. As in the SDK, every reading goes through the protected nsNow(), which a subclass may
 * override (motorlab's JVM test drives it from a simulated clock).
 */
public class ElapsedTime {
    public enum Resolution { SECONDS, MILLISECONDS }

    public static final long SECOND_IN_NANO = 1000000000L;
    public static final long MILLIS_IN_NANO = 1000000L;

    protected volatile long nsStartTime;
    protected final double resolution;

    public ElapsedTime() {
        this(Resolution.SECONDS);
    }

    public ElapsedTime(long startTime) {
        resolution = SECOND_IN_NANO;
        nsStartTime = startTime;
    }

    public ElapsedTime(Resolution resolution) {
        this.resolution = resolution == Resolution.SECONDS ? SECOND_IN_NANO : MILLIS_IN_NANO;
        reset();
    }

    protected long nsNow() {
        return System.nanoTime();
    }

    public long now(TimeUnit unit) {
        return unit.convert(nsNow(), TimeUnit.NANOSECONDS);
    }

    public void reset() {
        nsStartTime = nsNow();
    }

    public double startTime() {
        return nsStartTime / resolution;
    }

    public long startTimeNanoseconds() {
        return nsStartTime;
    }

    public double time() {
        return (nsNow() - nsStartTime) / resolution;
    }

    public long time(TimeUnit unit) {
        return unit.convert(nanoseconds(), TimeUnit.NANOSECONDS);
    }

    public double seconds() {
        return nanoseconds() * 1e-9;
    }

    public double milliseconds() {
        return nanoseconds() * 1e-6;
    }

    public long nanoseconds() {
        return nsNow() - nsStartTime;
    }

    @Override
    public String toString() {
        return String.format(Locale.US, "%.4f seconds", seconds());
    }
}
