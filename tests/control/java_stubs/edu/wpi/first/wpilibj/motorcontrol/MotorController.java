// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package edu.wpi.first.wpilibj.motorcontrol;
public interface MotorController { void setVoltage(double outputVolts); }
