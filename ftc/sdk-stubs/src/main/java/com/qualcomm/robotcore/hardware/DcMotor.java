// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.hardware;

/** Stub: the subset of DcMotor used by motorlab's OpModes and the official motor samples. */
public interface DcMotor extends DcMotorSimple {
    enum ZeroPowerBehavior { UNKNOWN, BRAKE, FLOAT }

    enum RunMode { RUN_WITHOUT_ENCODER, RUN_USING_ENCODER, RUN_TO_POSITION, STOP_AND_RESET_ENCODER }

    int getPortNumber();

    void setZeroPowerBehavior(ZeroPowerBehavior zeroPowerBehavior);

    ZeroPowerBehavior getZeroPowerBehavior();

    void setTargetPosition(int position);

    int getTargetPosition();

    boolean isBusy();

    int getCurrentPosition();

    void setMode(RunMode mode);

    RunMode getMode();
}
