// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.hardware;

import org.firstinspires.ftc.robotcore.external.navigation.CurrentUnit;

/** Stub: the subset of DcMotorEx used by motorlab's OpModes and ConceptMotorBulkRead. */
public interface DcMotorEx extends DcMotor {
    /** Encoder velocity [counts/s], from the bulk data when bulk caching is on. */
    double getVelocity();

    double getCurrent(CurrentUnit unit);
}
