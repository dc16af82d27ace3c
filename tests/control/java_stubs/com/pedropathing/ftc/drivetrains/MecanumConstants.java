// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.pedropathing.ftc.drivetrains;
public class MecanumConstants {
    public MecanumConstants xVelocity(double value) { return this; }
    public MecanumConstants yVelocity(double value) { return this; }
    public MecanumConstants nominalVoltage(double value) { return this; }
    public MecanumConstants staticFrictionCoefficient(double value) { return this; }
}
