// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.hardware;

/** Stub: the subset of TouchSensor used by the SensorTouch sample. */
public interface TouchSensor extends HardwareDevice {
    boolean isPressed();
}
