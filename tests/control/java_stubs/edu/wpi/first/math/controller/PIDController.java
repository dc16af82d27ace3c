// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package edu.wpi.first.math.controller;
public class PIDController {
    public PIDController(double kp, double ki, double kd, double period) {}
    public double calculate(double measurement, double setpoint) { return 0.0; }
}
