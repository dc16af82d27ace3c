// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.hardware;

public interface DcMotorSimple extends HardwareDevice {
    enum Direction {
        FORWARD, REVERSE;

        public Direction inverted() {
            return this == FORWARD ? REVERSE : FORWARD;
        }
    }

    void setDirection(Direction direction);

    Direction getDirection();

    void setPower(double power);

    double getPower();
}
