// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.hardware;

/** Stub: the subset of Servo used by the official servo samples (position only). */
public interface Servo extends HardwareDevice {
    /** Commands the servo to a position in [0, 1] (within the range set by scaleRange on the real SDK). */
    void setPosition(double position);
}
