// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.hardware;

/** Stub: the real interface adds read windows and heartbeats, which motorlab does not use. */
public interface I2cDeviceSynch extends I2cDeviceSynchSimple, Engagable {
}
