// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package org.firstinspires.ftc.robotcore.external;

/** A producer of a value, computed when asked (telemetry reads it at each transmission). */
public interface Func<T> {
    T value();
}
