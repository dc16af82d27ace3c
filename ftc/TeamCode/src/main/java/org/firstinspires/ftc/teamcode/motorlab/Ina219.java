/*
 * motorlab: INA219 bus-voltage and shunt-current monitor, as an FTC SDK I2C driver.
 * Written for motorlab from the TI INA219 data sheet (SBOS448G); see docs/ftc-robot.md.
 */
package org.firstinspires.ftc.teamcode.motorlab;

import com.qualcomm.robotcore.hardware.I2cAddr;
import com.qualcomm.robotcore.hardware.I2cDeviceSynch;
import com.qualcomm.robotcore.hardware.I2cDeviceSynchDevice;
import com.qualcomm.robotcore.hardware.I2cWaitControl;
import com.qualcomm.robotcore.hardware.configuration.annotations.DeviceProperties;
import com.qualcomm.robotcore.hardware.configuration.annotations.I2cDeviceType;
import java.util.Locale;

/**
 * TI INA219 (e.g. the Adafruit breakout with its 0.1 Ω shunt) on a REV hub I2C port.
 *
 * <p>Registers (16 bit, big-endian; data sheet section 8.6): 0 configuration, 1 shunt voltage (LSB
 * 10 µV, two's complement), 2 bus voltage (bits 15..3, LSB 4 mV; bit 1 conversion ready, bit 0 math
 * overflow), 3 power, 4 current, 5 calibration. The current register is shunt·cal/4096, so with
 * cal = trunc(0.04096 / (current_LSB·R_shunt)) it reads in units of current_LSB (eq. 1-2 of the data
 * sheet). The chip does not auto-increment its register pointer: every register is one I2C
 * write-then-read transaction.
 *
 * <p>Safety: {@link #readBusVoltage()} throws {@link OverVoltageException} when the bus is above
 * {@link Parameters#maxBusVoltage} (16 V by default). The data sheet's absolute maximum on IN+/IN- is
 * 26 V; seed 1 reports sensors destroyed above 16 V and asks never to exceed it, so that is the
 * default (and the top of the 16 V full-scale range the driver selects).
 */
@I2cDeviceType
@DeviceProperties(name = "INA219 current/voltage sensor (motorlab)", xmlTag = "MotorlabINA219",
        description = "TI INA219 bus voltage and shunt current monitor")
public class Ina219 extends I2cDeviceSynchDevice<I2cDeviceSynch> {
    /** A0 = A1 = GND. The chip answers at 0x40..0x4F depending on A0/A1. */
    public static final I2cAddr DEFAULT_ADDRESS = I2cAddr.create7bit(0x40);
    public static final int REG_CONFIGURATION = 0x00;
    public static final int REG_SHUNT_VOLTAGE = 0x01;
    public static final int REG_BUS_VOLTAGE = 0x02;
    public static final int REG_POWER = 0x03;
    public static final int REG_CURRENT = 0x04;
    public static final int REG_CALIBRATION = 0x05;
    /** Bus voltage LSB [V] and shunt voltage LSB [V]. */
    public static final double BUS_LSB = 0.004;
    public static final double SHUNT_LSB = 10e-6;
    /** Absolute maximum common-mode voltage of IN+/IN- [V] (data sheet 7.1). */
    public static final double ABSOLUTE_MAX_VOLTAGE = 26.0;

    /** Bus full-scale range (BRNG, configuration bit 13). */
    public enum BusRange {
        FSR_16V(0, 16.0), FSR_32V(1, 32.0);
        public final int code;
        public final double volts;

        BusRange(int code, double volts) {
            this.code = code;
            this.volts = volts;
        }
    }

    /** Shunt full-scale range: the PGA gain (PG, configuration bits 12..11). */
    public enum ShuntRange {
        MV_40(0, 0.040), MV_80(1, 0.080), MV_160(2, 0.160), MV_320(3, 0.320);
        public final int code;
        public final double volts;

        ShuntRange(int code, double volts) {
            this.code = code;
            this.volts = volts;
        }
    }

    /** ADC resolution or averaging (BADC/SADC codes) and the conversion time of each [µs]. */
    public enum Adc {
        BITS_9(0x0, 1, 84), BITS_10(0x1, 1, 148), BITS_11(0x2, 1, 276), BITS_12(0x3, 1, 532),
        AVG_2(0x9, 2, 1060), AVG_4(0xA, 4, 2130), AVG_8(0xB, 8, 4260), AVG_16(0xC, 16, 8510),
        AVG_32(0xD, 32, 17020), AVG_64(0xE, 64, 34050), AVG_128(0xF, 128, 68100);
        public final int code;
        public final int samples;
        public final int conversionMicros;

        Adc(int code, int samples, int conversionMicros) {
            this.code = code;
            this.samples = samples;
            this.conversionMicros = conversionMicros;
        }
    }

    /** What configure() programs. Defaults: Adafruit breakout, 16 V range, ±320 mV, 2-sample averages. */
    public static class Parameters {
        public I2cAddr address = DEFAULT_ADDRESS;
        /** Shunt resistance [Ω] (0.1 Ω on the Adafruit breakout). */
        public double shuntOhms = 0.1;
        /** Largest current to measure [A]; sets the current LSB (≈ maxExpectedCurrent/32767). */
        public double maxExpectedCurrent = 3.2;
        public BusRange busRange = BusRange.FSR_16V;
        public ShuntRange shuntRange = ShuntRange.MV_320;
        public Adc busAdc = Adc.AVG_2;
        public Adc shuntAdc = Adc.AVG_2;
        /** Refuse (throw) above this bus voltage [V]. */
        public double maxBusVoltage = 16.0;

        public Parameters copy() {
            Parameters p = new Parameters();
            p.address = address;
            p.shuntOhms = shuntOhms;
            p.maxExpectedCurrent = maxExpectedCurrent;
            p.busRange = busRange;
            p.shuntRange = shuntRange;
            p.busAdc = busAdc;
            p.shuntAdc = shuntAdc;
            p.maxBusVoltage = maxBusVoltage;
            return p;
        }
    }

    /** Thrown when the bus voltage exceeds the configured maximum: cut the power. */
    public static class OverVoltageException extends IllegalStateException {
        private static final long serialVersionUID = 1L;
        public final double busVoltage;

        public OverVoltageException(double busVoltage, double limit) {
            super(String.format(Locale.US, "INA219 bus voltage %.2f V is above %.1f V: power cut, refusing to run",
                    busVoltage, limit));
            this.busVoltage = busVoltage;
        }
    }

    private Parameters parameters = new Parameters();
    private int calibration;
    private double currentLsb;
    private boolean overflow;

    public Ina219(I2cDeviceSynch deviceClient, boolean deviceClientIsOwned) {
        super(deviceClient, deviceClientIsOwned);
        this.deviceClient.setI2cAddress(parameters.address);
        super.registerArmingStateCallback(false);
        this.deviceClient.engage();
    }

    @Override
    protected synchronized boolean doInitialize() {
        return configure(parameters);
    }

    /**
     * Reset the chip and program configuration and calibration; true when both read back as written.
     *
     * @throws IllegalArgumentException for impossible parameters (the message says which)
     */
    public synchronized boolean configure(Parameters p) {
        checkParameters(p);
        parameters = p.copy();
        deviceClient.setI2cAddress(p.address);
        calibration = calibrationFor(p.shuntOhms, p.maxExpectedCurrent);
        currentLsb = 0.04096 / (calibration * p.shuntOhms);
        writeRegister(REG_CONFIGURATION, 0x8000); // RST: all registers to their defaults
        writeRegister(REG_CONFIGURATION, configurationWord(p));
        writeRegister(REG_CALIBRATION, calibration);
        deviceClient.waitForWriteCompletions(I2cWaitControl.WRITTEN);
        return readRegister(REG_CONFIGURATION) == configurationWord(p) && readRegister(REG_CALIBRATION) == calibration;
    }

    static void checkParameters(Parameters p) {
        if (!(p.shuntOhms > 0) || Double.isInfinite(p.shuntOhms)) {
            throw new IllegalArgumentException("INA219: shunt resistance must be positive, got " + p.shuntOhms);
        }
        if (!(p.maxExpectedCurrent > 0) || p.maxExpectedCurrent * p.shuntOhms > p.shuntRange.volts * (1 + 1e-9)) {
            throw new IllegalArgumentException(String.format(Locale.US,
                    "INA219: %.3g A through %.3g Ω is outside the ±%.0f mV shunt range", p.maxExpectedCurrent,
                    p.shuntOhms, p.shuntRange.volts * 1e3));
        }
        if (!(p.maxBusVoltage > 0) || p.maxBusVoltage > Math.min(p.busRange.volts, ABSOLUTE_MAX_VOLTAGE)) {
            throw new IllegalArgumentException(String.format(Locale.US,
                    "INA219: a bus limit of %.1f V is above the %.0f V range or the chip's %.0f V maximum",
                    p.maxBusVoltage, p.busRange.volts, ABSOLUTE_MAX_VOLTAGE));
        }
    }

    /** Calibration register: trunc(0.04096/(LSB·R)) with LSB = I_max/32767, even (bit 0 is void), ≤ 0xFFFE. */
    public static int calibrationFor(double shuntOhms, double maxExpectedCurrent) {
        double lsb = maxExpectedCurrent / 32767.0;
        // The tiny relative margin keeps an exact quotient (the data sheet's 0.1 Ω, 100 µA: 4096) from
        // flooring to one less through rounding.
        long cal = (long) Math.floor(0.04096 / (lsb * shuntOhms) * (1 + 1e-12));
        cal = Math.min(cal, 0xFFFE) & 0xFFFE;
        if (cal < 2) {
            throw new IllegalArgumentException("INA219: current LSB too coarse for this shunt");
        }
        return (int) cal;
    }

    /** Configuration register: BRNG, PG, BADC, SADC and mode 7 (shunt and bus, continuous). */
    public static int configurationWord(Parameters p) {
        return (p.busRange.code << 13) | (p.shuntRange.code << 11) | (p.busAdc.code << 7) | (p.shuntAdc.code << 3) | 0x7;
    }

    /**
     * Bus voltage [V] (IN- to GND).
     *
     * @throws OverVoltageException at or above the limit: a reading at the top of the 16 V range may be
     *     a saturated one, so reaching the limit already counts as exceeding it
     */
    public double readBusVoltage() {
        int raw = readRegister(REG_BUS_VOLTAGE);
        overflow = (raw & 0x1) != 0;
        double volts = (raw >> 3) * BUS_LSB;
        if (volts >= parameters.maxBusVoltage) {
            throw new OverVoltageException(volts, parameters.maxBusVoltage);
        }
        return volts;
    }

    /** Shunt voltage IN+ − IN- [V]. */
    public double readShuntVoltage() {
        return (short) readRegister(REG_SHUNT_VOLTAGE) * SHUNT_LSB;
    }

    /** Current through the shunt [A], from the current register (needs the calibration). */
    public double readCurrent() {
        return (short) readRegister(REG_CURRENT) * currentLsb;
    }

    /** Power [W] (LSB 20·current LSB). */
    public double readPower() {
        return readRegister(REG_POWER) * 20.0 * currentLsb;
    }

    /**
     * True when {@code current} [A] is at the end of the shunt range (±range/R, 3.2 A for 0.1 Ω and
     * ±320 mV): the shunt voltage was clipped and the true current may be larger.
     */
    public boolean isSaturated(double current) {
        return Math.abs(current) >= 0.995 * parameters.shuntRange.volts / parameters.shuntOhms;
    }

    /** True when the last bus-voltage read flagged a math overflow (current or power out of range). */
    public boolean overflowed() {
        return overflow;
    }

    public double getCurrentLsb() {
        return currentLsb;
    }

    public int getCalibration() {
        return calibration;
    }

    public Parameters getParameters() {
        return parameters.copy();
    }

    /** Time for one new bus+shunt pair in continuous mode [ms]. */
    public double conversionMillis() {
        return (parameters.busAdc.conversionMicros + parameters.shuntAdc.conversionMicros) / 1000.0;
    }

    public int readRegister(int register) {
        byte[] data = deviceClient.read(register, 2);
        return ((data[0] & 0xFF) << 8) | (data[1] & 0xFF);
    }

    public void writeRegister(int register, int value) {
        deviceClient.write(register, new byte[] {(byte) (value >> 8), (byte) value}, I2cWaitControl.WRITTEN);
    }

    @Override
    public Manufacturer getManufacturer() {
        return Manufacturer.Adafruit;
    }

    @Override
    public String getDeviceName() {
        return "INA219 current/voltage sensor (motorlab)";
    }
}
