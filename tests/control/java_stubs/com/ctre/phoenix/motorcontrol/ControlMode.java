// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.ctre.phoenix.motorcontrol;
public enum ControlMode { PercentOutput, Position, Velocity }
