// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.eventloop.opmode;

/** Stub: only the type is needed (the second argument of the HardwareMap constructor). */
public interface OpModeManagerNotifier {
}
