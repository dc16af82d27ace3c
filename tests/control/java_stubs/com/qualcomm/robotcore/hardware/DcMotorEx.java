// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.qualcomm.robotcore.hardware;
public interface DcMotorEx extends DcMotor {
    double getVelocity();
    void setVelocity(double angularRate);
    void setVelocityPIDFCoefficients(double p, double i, double d, double f);
}
